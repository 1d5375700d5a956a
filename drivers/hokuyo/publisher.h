// The thin publishing layer: RangeScan -> selfcal.range_scan_t on the bus, through a
// QueuedPublisher so the receive loop never blocks on publishing. Slots are allocated once at
// start; when the bus falls behind by `capacity` scans, the newest scan is dropped and counted.
#pragma once

#include <cstdint>
#include <string>

#include "drivers/hokuyo/driver.h"
#include "protocols/bus/queued_publisher.h"
#include "selfcal/range_scan_t.hpp"

namespace selfcal::hokuyo {

// The LCM message for a scan (every field as commented in range_scan_t.lcm).
void ToMessage(const RangeScan& scan, range_scan_t& message);

class ScanPublisher {
 public:
  ScanPublisher(Bus& bus, std::string channel, std::size_t capacity = 16,
                std::size_t max_values = 1081);

  // Copies the scan into a free slot; never blocks on the bus.
  void Submit(const RangeScan& scan);
  // Waits until every submitted scan is published (for tests and shutdown).
  void Flush() { queue_.Flush(); }

  std::int64_t published() const { return queue_.stats().published; }
  std::int64_t dropped() const { return queue_.stats().dropped; }
  std::int64_t failed() const { return queue_.stats().failed; }

 private:
  QueuedPublisher<range_scan_t> queue_;
};

}  // namespace selfcal::hokuyo
