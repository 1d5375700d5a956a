// The publishing side of selfcal-wenglor: profiles as selfcal.line_profile_t through a
// QueuedPublisher, so that the receive loop never waits on LCM and keeps draining the library's
// FIFO; when the queue is full the newest profile is dropped and counted.
#pragma once

#include <cstdint>
#include <string>

#include "drivers/wenglor/wenglor_scanner.h"
#include "protocols/bus/queued_publisher.h"
#include "selfcal/line_profile_t.hpp"

namespace selfcal::wenglor {

// Fills `message` from `profile` (utime, device time and counter, x/z in m, intensity).
void ToLineProfile(const Profile& profile, selfcal::line_profile_t& message);

struct PublisherStats {
  std::int64_t published = 0;
  std::int64_t dropped_queue_full = 0;
  std::int64_t publish_errors = 0;
};

class ProfilePublisher {
 public:
  ProfilePublisher(Bus& bus, std::string channel, int queue_profiles, int columns);

  // Copies `profile` into the queue (no allocation); false when the queue was full or the profile
  // is wider than `columns`.
  bool Push(const Profile& profile);
  // Publishes what is queued, then stops the thread.
  void Stop() { queue_.Stop(); }
  PublisherStats stats() const;
  std::string last_error() const { return queue_.last_error(); }

 private:
  int columns_;
  QueuedPublisher<selfcal::line_profile_t> queue_;
};

}  // namespace selfcal::wenglor
