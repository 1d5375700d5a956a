#include "core/timing/host_clock.h"

#include <ctime>

namespace selfcal::timing {
namespace {

std::int64_t Nanoseconds(const timespec& ts) {
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

timespec Read(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return ts;
}

}  // namespace

std::int64_t RealtimeNs() { return Nanoseconds(Read(CLOCK_REALTIME)); }

std::int64_t RealtimeUs() { return RealtimeNs() / 1000; }

std::int64_t MonotonicNs() { return Nanoseconds(Read(CLOCK_MONOTONIC)); }

double MonotonicUs() {
  const timespec ts = Read(CLOCK_MONOTONIC);
  return static_cast<double>(ts.tv_sec) * 1e6 + static_cast<double>(ts.tv_nsec) * 1e-3;
}

double RealtimeMinusMonotonicUs() {
  const timespec mono = Read(CLOCK_MONOTONIC);
  const timespec real = Read(CLOCK_REALTIME);
  return (static_cast<double>(real.tv_sec) - static_cast<double>(mono.tv_sec)) * 1e6 +
         (static_cast<double>(real.tv_nsec) - static_cast<double>(mono.tv_nsec)) * 1e-3;
}

}  // namespace selfcal::timing
