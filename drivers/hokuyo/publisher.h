// The thin publishing layer: RangeScan -> selfcal.range_scan_t on the bus, on a thread of its
// own so the receive loop never blocks on publishing. Slots are allocated once at start; when
// the bus falls behind by `capacity` scans, the newest scan is dropped and counted.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "drivers/hokuyo/driver.h"
#include "protocols/bus/bus.h"
#include "selfcal/range_scan_t.hpp"

namespace selfcal::hokuyo {

// The LCM message for a scan (every field as commented in range_scan_t.lcm).
void ToMessage(const RangeScan& scan, range_scan_t& message);

class ScanPublisher {
 public:
  ScanPublisher(Bus& bus, std::string channel, std::size_t capacity = 16,
                std::size_t max_values = 1081);
  ~ScanPublisher();

  // Copies the scan into a free slot; never blocks on the bus.
  void Submit(const RangeScan& scan);
  // Waits until every submitted scan is published (for tests and shutdown).
  void Flush();

  std::int64_t published() const { return published_.load(); }
  std::int64_t dropped() const { return dropped_.load(); }
  std::int64_t failed() const { return failed_.load(); }

 private:
  void Loop();

  Bus& bus_;
  std::string channel_;
  std::vector<range_scan_t> slots_;
  std::vector<std::uint8_t> encoded_;
  std::size_t head_ = 0;  // next slot to publish
  std::size_t size_ = 0;  // slots waiting
  std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable drained_;
  bool stop_ = false;
  bool busy_ = false;
  std::atomic<std::int64_t> published_{0};
  std::atomic<std::int64_t> dropped_{0};
  std::atomic<std::int64_t> failed_{0};
  std::thread thread_;
};

}  // namespace selfcal::hokuyo
