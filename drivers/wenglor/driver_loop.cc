#include "drivers/wenglor/driver_loop.h"

#include <algorithm>
#include <chrono>
#include <string>
#include <thread>

namespace selfcal::wenglor {
namespace {

// Sleeps `duration` in short slices so that a stop request is seen quickly.
void SleepUnlessStopped(std::chrono::microseconds duration, const std::atomic<bool>& stop) {
  const auto deadline = std::chrono::steady_clock::now() + duration;
  while (!stop.load(std::memory_order_relaxed)) {
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline) return;
    std::this_thread::sleep_for(std::min<std::chrono::steady_clock::duration>(
        deadline - now, std::chrono::milliseconds(20)));
  }
}

}  // namespace

void RunScanner(WenglorScanner& scanner, const std::atomic<bool>& stop, const ProfileSink& sink,
                const std::function<void()>& tick, std::chrono::milliseconds tick_interval) {
  auto next_tick = std::chrono::steady_clock::now() + tick_interval;
  const auto& config = scanner.config();
  const auto reconnect_interval = std::chrono::milliseconds(config.reconnect_interval_ms);
  const auto poll_interval = std::chrono::microseconds(config.poll_interval_us);
  Profile profile;
  profile.Allocate(scanner.capacity());
  while (!stop.load(std::memory_order_relaxed)) {
    if (tick && std::chrono::steady_clock::now() >= next_tick) {
      next_tick += tick_interval;
      tick();
    }
    if (!scanner.connected()) {
      const Status status = scanner.Connect();
      if (!status.ok()) {
        scanner.Log(LogLevel::kError, "connection failed: " + status.error().message +
                                          "; retrying in " +
                                          std::to_string(config.reconnect_interval_ms) + " ms");
        SleepUnlessStopped(reconnect_interval, stop);
        continue;
      }
    }
    switch (scanner.Poll(profile)) {
      case PollResult::kProfile:
        sink(profile);
        break;
      case PollResult::kDropped:
        break;
      case PollResult::kNoNewScan:
        if (poll_interval.count() > 0) std::this_thread::sleep_for(poll_interval);
        break;
      case PollResult::kLinkLost:
        scanner.Disconnect();
        SleepUnlessStopped(reconnect_interval, stop);
        break;
    }
  }
  scanner.Disconnect();
}

}  // namespace selfcal::wenglor
