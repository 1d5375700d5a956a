// The host clocks read as the system does: the units agree with each other and with <chrono>,
// and the monotonic clock never goes back.
#include "core/timing/host_clock.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdint>

namespace selfcal::timing {
namespace {

std::int64_t ChronoRealtimeUs() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::int64_t ChronoMonotonicNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

TEST(HostClock, RealtimeIsTheSystemClockInMicrosecondsAndNanoseconds) {
  const std::int64_t before = ChronoRealtimeUs();
  const std::int64_t us = RealtimeUs();
  const std::int64_t ns = RealtimeNs();
  const std::int64_t after = ChronoRealtimeUs();
  EXPECT_GE(us, before);
  EXPECT_LE(us, after);
  EXPECT_GE(ns / 1000, us);
  EXPECT_LE(ns / 1000, after);
}

TEST(HostClock, MonotonicIsSteadyClockInNanosecondsAndMicroseconds) {
  const std::int64_t before = ChronoMonotonicNs();
  const std::int64_t ns = MonotonicNs();
  const double us = MonotonicUs();
  const std::int64_t after = ChronoMonotonicNs();
  EXPECT_GE(ns, before);
  EXPECT_LE(ns, after);
  EXPECT_GE(us, static_cast<double>(ns) * 1e-3);
  EXPECT_LE(us, static_cast<double>(after) * 1e-3 + 1.0);  // one microsecond of double rounding
}

TEST(HostClock, MonotonicNeverGoesBack) {
  std::int64_t last = MonotonicNs();
  for (int i = 0; i < 100000; ++i) {
    const std::int64_t now = MonotonicNs();
    ASSERT_GE(now, last) << "after " << i << " reads";
    last = now;
  }
}

TEST(HostClock, RealtimeMinusMonotonicTurnsAMonotonicTimeIntoUtime) {
  const double offset = RealtimeMinusMonotonicUs();
  const double utime = MonotonicUs() + offset;
  // Within 50 ms: the reads are microseconds apart unless the scheduler stalls the test.
  EXPECT_LT(std::abs(utime - static_cast<double>(RealtimeUs())), 50e3);
  EXPECT_LT(std::abs(RealtimeMinusMonotonicUs() - offset), 50e3);
}

}  // namespace
}  // namespace selfcal::timing
