#include "protocols/camera/device_clock.h"

#include <gtest/gtest.h>

#include <random>

namespace selfcal::camera {
namespace {

constexpr std::int64_t kMs = 1'000'000;

TEST(DeviceClock, FollowsOffsetAndDriftDespiteVariableDelay) {
  DeviceClockMap clock;
  std::mt19937 rng(3);
  std::uniform_int_distribution<std::int64_t> delay(2 * kMs, 12 * kMs);  // 2 ms minimum delay
  const std::int64_t host_epoch = 1'700'000'000'000'000'000;
  const double drift = 50e-6;  // the device clock runs 50 ppm slow
  std::int64_t worst = 0;
  for (int i = 0; i < 600; ++i) {  // 30 s at 20 Hz
    const std::int64_t device = 123 * kMs + i * 50 * kMs;
    const auto exposure = host_epoch + static_cast<std::int64_t>((i * 50 * kMs) * (1.0 + drift));
    const std::int64_t mapped = clock.Map(device, exposure + delay(rng));
    EXPECT_LE(mapped - exposure, 12 * kMs);
    if (i >= 256) worst = std::max(worst, std::abs(mapped - exposure - 2 * kMs));
  }
  // After a full window the bias is the minimum delay, up to the jitter of its estimate.
  EXPECT_LT(worst, 1 * kMs);
  // Minima of 128 delays uniform over 10 ms sit within ~0.1 ms of the bound, 6.4 s apart.
  EXPECT_NEAR(clock.skew(), 1.0 + drift, 30e-6);
  EXPECT_EQ(clock.resets(), 0);
}

TEST(DeviceClock, DeviceRestartResetsTheFilter) {
  DeviceClockMap clock;
  const std::int64_t host = 1'700'000'000'000'000'000;
  for (int i = 0; i < 100; ++i) clock.Map(5'000 * kMs + i * 33 * kMs, host + i * 33 * kMs + kMs);
  // The camera restarts: its clock begins again near zero.
  const std::int64_t restart_host = host + 200 * 33 * kMs;
  EXPECT_EQ(clock.Map(10 * kMs, restart_host + kMs), restart_host + kMs);
  EXPECT_EQ(clock.resets(), 1);
  EXPECT_EQ(clock.Map(43 * kMs, restart_host + 34 * kMs), restart_host + 34 * kMs);
  // A host-side pause of many seconds with a steady device clock is not a reset...
  // ...but a device clock 2 s off the line is.
  clock.Map(76 * kMs + 2'000 * kMs, restart_host + 67 * kMs);
  EXPECT_EQ(clock.resets(), 2);
}

}  // namespace
}  // namespace selfcal::camera
