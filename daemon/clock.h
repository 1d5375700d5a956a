// The daemon's time, read through a Clock so that tests can run sessions in simulated time
// instead of waiting for them. Two clocks: wall time (CLOCK_REALTIME, LCM's utime) only for stamps
// and for a request's age, which the sender signed in wall time; CLOCK_MONOTONIC for every
// interval and timeout, so that a step of the wall clock (NTP, an operator) neither stalls the
// motion and the status nor ages anything.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>

#include "core/timing/host_clock.h"

namespace selfcal::daemon {

std::int64_t Us(double seconds);      // seconds -> [us]
std::string Millis(std::int64_t us);  // "12.5 ms", for messages

class Clock {
 public:
  virtual ~Clock() = default;
  virtual std::int64_t Now() const = 0;        // wall time [us since the epoch]: stamps only
  virtual std::int64_t Monotonic() const = 0;  // [us]: intervals and timeouts
};

class SystemClock final : public Clock {
 public:
  std::int64_t Now() const override { return timing::RealtimeUs(); }
  std::int64_t Monotonic() const override { return timing::MonotonicNs() / 1000; }
};

// Time that moves only when told; safe to read from other threads (the engine worker).
class ManualClock final : public Clock {
 public:
  explicit ManualClock(std::int64_t start_utime) : wall_(start_utime), monotonic_(1'000'000) {}
  std::int64_t Now() const override { return wall_.load(); }
  std::int64_t Monotonic() const override { return monotonic_.load(); }
  void Advance(std::int64_t us) {
    wall_ += us;
    monotonic_ += us;
  }
  // A step of the wall clock alone (NTP, an operator's date -s); monotonic time does not move.
  void StepWall(std::int64_t us) { wall_ += us; }

 private:
  std::atomic<std::int64_t> wall_;
  std::atomic<std::int64_t> monotonic_;
};

}  // namespace selfcal::daemon
