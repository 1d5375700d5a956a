// The publishing side of selfcal-wenglor: a bounded queue of preallocated profiles between the
// receive loop and a publisher thread, so that the receive loop never waits on LCM. When the queue
// is full the newest profile is dropped and counted (the receive loop must keep draining the
// library's FIFO, or the sensor's profiles would be lost there instead, uncounted).
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "drivers/wenglor/wenglor_scanner.h"
#include "protocols/bus/bus.h"
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
  ~ProfilePublisher();
  ProfilePublisher(const ProfilePublisher&) = delete;
  ProfilePublisher& operator=(const ProfilePublisher&) = delete;

  // Copies `profile` into the queue (no allocation); false when the queue was full.
  bool Push(const Profile& profile);
  // Publishes what is queued, then stops the thread.
  void Stop();
  PublisherStats stats() const;
  std::string last_error() const;

 private:
  void Run();

  Bus& bus_;
  std::string channel_;
  std::vector<Profile> slots_;
  std::size_t head_ = 0;  // next slot to publish
  std::size_t size_ = 0;  // queued profiles
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::atomic<std::int64_t> published_{0};
  std::atomic<std::int64_t> dropped_{0};
  std::atomic<std::int64_t> errors_{0};
  std::string last_error_;
  std::thread thread_;
};

}  // namespace selfcal::wenglor
