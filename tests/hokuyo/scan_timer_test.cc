// The scan timer on synthetic data with a known truth: a mirror not locked to the millisecond
// counter, lost scans, a counter that jumps.
#include "drivers/hokuyo/scan_timer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace selfcal::hokuyo {
namespace {

TEST(ScanTimer, VernierResolvesTheScanPhase) {
  // Mirror period 25 ms * (1 + 1e-3) in device time; timestamps floor to the millisecond.
  const double period = 25000 * 1.001;
  const double phase = 123456.789;
  ScanTimer timer(25000);
  double worst_after_warmup = 0;
  for (int n = 0; n < 400; ++n) {
    const double truth = phase + n * period;
    const auto ts = static_cast<std::int64_t>(std::floor(truth / 1000));
    const double estimate = timer.Add(ts);
    if (n >= 100) worst_after_warmup = std::max(worst_after_warmup, std::abs(estimate - truth));
  }
  std::printf("scan timer: worst error after 100 scans %.1f us, period %.3f us\n",
              worst_after_warmup, timer.period_us());
  EXPECT_LT(worst_after_warmup, 60);
  EXPECT_NEAR(timer.period_us(), period, 0.5);
}

TEST(ScanTimer, LostScansKeepTheirPlaceOnTheGrid) {
  const double period = 25000 * 0.9995;
  ScanTimer timer(25000);
  for (int n = 0; n < 200; ++n) {
    if (n % 7 == 3 || (n > 100 && n < 110)) continue;  // lost
    const double truth = 5000.5 + n * period;
    timer.Add(static_cast<std::int64_t>(std::floor(truth / 1000)));
    EXPECT_EQ(timer.last_index(), n);
  }
}

TEST(ScanTimer, ACounterThatJumpsIsATypedClockJump) {
  ScanTimer timer(25000);
  EXPECT_EQ(timer.Check(123456), timing::ClockJump::kNone);  // nothing to continue yet
  timer.Add(123456);
  timer.Add(123481);
  EXPECT_EQ(timer.Check(123506), timing::ClockJump::kNone);
  EXPECT_EQ(timer.Check(123506 + 59000), timing::ClockJump::kNone);  // lost scans, not a jump
  EXPECT_EQ(timer.Check(1000), timing::ClockJump::kBackwards);       // a reboot
  EXPECT_EQ(timer.Check(123481 + 60001), timing::ClockJump::kForward);
}

}  // namespace
}  // namespace selfcal::hokuyo
