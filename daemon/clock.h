// The daemon's time: CLOCK_REALTIME in microseconds, as LCM's utime, read through a Clock so
// that tests can run sessions in simulated time instead of waiting for them.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>

namespace selfcal::daemon {

std::int64_t NowUtime();  // CLOCK_REALTIME [us]

std::int64_t Us(double seconds);      // seconds -> [us]
std::string Millis(std::int64_t us);  // "12.5 ms", for messages

class Clock {
 public:
  virtual ~Clock() = default;
  virtual std::int64_t Now() const = 0;  // [us since the epoch]
};

class SystemClock final : public Clock {
 public:
  std::int64_t Now() const override { return NowUtime(); }
};

// Time that moves only when told; safe to read from other threads (the engine worker).
class ManualClock final : public Clock {
 public:
  explicit ManualClock(std::int64_t start_utime) : now_(start_utime) {}
  std::int64_t Now() const override { return now_.load(); }
  void Advance(std::int64_t us) { now_ += us; }

 private:
  std::atomic<std::int64_t> now_;
};

}  // namespace selfcal::daemon
