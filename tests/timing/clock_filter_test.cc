// The receive-time clock filter on synthetic data with a known truth, with the parameters each
// kind of device uses: FRI / CANopen (the defaults), camera frames (protocols/camera), the
// Wenglor's never-early mapping. Simulated time.
#include "core/timing/clock_filter.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include "protocols/camera/frame_clock.h"

namespace selfcal::timing {
namespace {

// ---- Defaults (FRI monitoring messages, CANopen SYNC) -------------------------------------------

TEST(ClockFilter, FollowsDriftAtOneKilohertzAndSettles) {
  ClockFilter clock;
  std::mt19937 random(5);
  std::uniform_int_distribution<std::int64_t> delay(20, 300);  // us
  const std::int64_t host_epoch = 1'700'000'000'000'000;
  const double drift = -40e-6;  // host seconds per device second - 1
  double worst = 0;
  for (int k = 0; k < 3000; ++k) {  // 3 s at 1 kHz
    const std::int64_t device = 5'000'000 + k * 1000;
    const auto instant = host_epoch + static_cast<std::int64_t>(k * 1000 * (1 + drift));
    EXPECT_EQ(clock.Add(device, instant + delay(random)), ClockJump::kNone);
    EXPECT_EQ(clock.settled(), k >= 500) << k;  // 0.5 s and 50 samples, every bin filled
    if (clock.settled()) {
      worst = std::max(worst, std::abs(static_cast<double>(clock.ToHost(device) - instant)));
    }
  }
  std::printf("1 kHz, delays 20..300 us, -40 ppm: worst error %.0f us, drift %.1f ppm\n", worst,
              clock.drift_ppm());
  // The bias is the smallest delay of the window (20 us), up to how well the minima find it.
  EXPECT_LT(worst, 60.0);
  EXPECT_NEAR(clock.drift_ppm(), -40.0, 10.0);
  EXPECT_EQ(clock.restarts(), 0);
}

TEST(ClockFilter, JumpsRestartTheFilterAndSayWhy) {
  ClockFilter clock;
  const std::int64_t host = 1'700'000'000'000'000;
  for (int k = 0; k < 100; ++k)
    ASSERT_EQ(clock.Add(k * 1000, host + k * 1000 + 50), ClockJump::kNone);
  EXPECT_EQ(clock.Add(99'000, host + 100'050), ClockJump::kBackwards);  // stood still
  EXPECT_EQ(clock.restarts(), 1);
  EXPECT_EQ(clock.size(), 1u);
  EXPECT_EQ(clock.ToHost(99'000), host + 100'050);  // the first sample maps to its receive time
  EXPECT_EQ(clock.Add(100'000, host + 101'050), ClockJump::kNone);
  // 0.2 s later in host time than the device clock says: off the line.
  EXPECT_EQ(clock.Add(101'000, host + 302'050), ClockJump::kOffTheLine);
  EXPECT_EQ(clock.restarts(), 2);
  clock.Reset();
  EXPECT_EQ(clock.size(), 0u);
  EXPECT_EQ(clock.restarts(), 2);  // Reset is not a jump
}

TEST(ClockFilter, ByDefaultFollowsARateFarFromOne) {
  // A SYNC clock counted at a configured 10 ms whose SYNCs really come every 30 ms: the device
  // time is a count times the wrong period, which no drift bound may refuse.
  ClockFilterOptions options;
  options.settle_s = 0.02;
  options.settle_samples = 3;
  options.bins = 3;
  ClockFilter clock(options);
  const std::int64_t host = 1'700'000'000'000'000;
  for (int k = 0; k < 40; ++k) {
    EXPECT_EQ(clock.Add(k * 10'000, host + k * 30'000 + 200), ClockJump::kNone) << k;
  }
  EXPECT_TRUE(clock.settled());
  EXPECT_NEAR(clock.rate(), 3.0, 1e-9);
  EXPECT_EQ(clock.ToHost(39 * 10'000), host + 39 * 30'000 + 200);
  EXPECT_EQ(clock.restarts(), 0);
}

// A 500 Hz stream (an FRI controller at 2 ms) whose receive time is `receive(sent)` plus 20-60 us;
// returns the worst error of the newest sample's mapping once settled, as a driver publishes it.
template <typename Receive>
double WorstPublishedErrorUs(ClockFilter& clock, double seconds, Receive receive) {
  std::mt19937 random(7);
  std::uniform_int_distribution<std::int64_t> delay(20, 60);
  const std::int64_t host_epoch = 1'700'000'000'000'000;
  const double drift = -50e-6;
  double worst = 0;
  for (int k = 0; k < static_cast<int>(seconds * 500); ++k) {
    const std::int64_t device = 7'000'000 + k * 2000;
    const auto sent = static_cast<std::int64_t>(k * 2000 * (1 + drift));
    (void)clock.Add(device, host_epoch + receive(sent) + delay(random));
    if (clock.settled()) {
      const auto error = clock.ToHost(device) - (host_epoch + sent);
      worst = std::max(worst, std::abs(static_cast<double>(error)));
    }
  }
  return worst;
}

TEST(ClockFilter, ABacklogReadInABurstAtStartDoesNotBendTheLine) {
  // The reader starts late: what the device sent meanwhile arrives at once, 5 us apart.
  const auto backlog = [](std::int64_t backlog_us) {
    return [backlog_us](std::int64_t sent) { return std::max(sent, backlog_us + sent / 400); };
  };
  ClockFilterOptions fri;
  fri.max_drift = 1e-3;  // selfcal-iiwa's bound
  for (const std::int64_t backlog_us : {100'000, 300'000, 600'000}) {
    ClockFilter bounded(fri), unbounded;
    const double worst_bounded = WorstPublishedErrorUs(bounded, 4.0, backlog(backlog_us));
    const double worst_unbounded = WorstPublishedErrorUs(unbounded, 4.0, backlog(backlog_us));
    std::printf("backlog %.1f s at start: worst error %.0f us (drift bounded), %.0f us (not)\n",
                static_cast<double>(backlog_us) * 1e-6, worst_bounded, worst_unbounded);
    EXPECT_LT(worst_bounded, 500.0) << backlog_us;
    // Unbounded, a backlog shorter than the settling span is dropped on the first late sample.
    if (backlog_us < 500'000) {
      EXPECT_LT(worst_unbounded, 100.0) << backlog_us;
    }
  }
}

TEST(ClockFilter, AReaderThatStallsKeepsTheMapping) {
  for (const std::int64_t stall_us : {150'000, 500'000, 900'000}) {
    // From 2 s on the reader sleeps; then it reads the backlog at 5 us a message.
    const std::int64_t from = 2'000'000, to = from + stall_us;
    ClockFilter clock;
    const double worst = WorstPublishedErrorUs(clock, 5.0, [&](std::int64_t sent) {
      return sent >= from && sent < to ? to + (sent - from) / 400 : sent;
    });
    std::printf("reader stalled %.2f s: worst error %.0f us, %lld restarts\n",
                static_cast<double>(stall_us) * 1e-6, worst,
                static_cast<long long>(clock.restarts()));
    EXPECT_LT(worst, 100.0) << stall_us;
    EXPECT_EQ(clock.restarts(), 0) << stall_us;
    EXPECT_TRUE(clock.settled());
  }
}

TEST(ClockFilter, AHostClockStepRestartsOnceItOutlastsAStall) {
  ClockFilter clock;
  const std::int64_t host = 1'700'000'000'000'000;
  int k = 0;
  for (; k < 1000; ++k) ASSERT_EQ(clock.Add(k * 2000, host + k * 2000 + 50), ClockJump::kNone);
  ASSERT_TRUE(clock.settled());
  // The host clock steps 0.3 s ahead: late samples, but not caught up as a backlog would be.
  std::vector<ClockJump> jumps;
  for (; k < 1400; ++k) {
    const ClockJump jump = clock.Add(k * 2000, host + 300'000 + k * 2000 + 50);
    if (jump != ClockJump::kNone) jumps.push_back(jump);
  }
  ASSERT_EQ(jumps, std::vector<ClockJump>{ClockJump::kOffTheLine});
  EXPECT_EQ(clock.restarts(), 1);
  EXPECT_EQ(clock.ToHost((k - 1) * 2000), host + 300'000 + (k - 1) * 2000 + 50);
  // Received before the line says it was sent: a jump at once.
  EXPECT_EQ(clock.Add(k * 2000, host + k * 2000), ClockJump::kOffTheLine);
}

// ---- Camera frames ------------------------------------------------------------------------------

constexpr std::int64_t kMs = 1'000;  // us

TEST(ClockFilterFrames, FollowsOffsetAndDriftDespiteVariableDelay) {
  ClockFilter clock(camera::FrameClockOptions());
  std::mt19937 rng(3);
  std::uniform_int_distribution<std::int64_t> delay(2 * kMs, 12 * kMs);  // 2 ms minimum delay
  const std::int64_t host_epoch = 1'700'000'000'000'000;
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
  EXPECT_NEAR(clock.rate(), 1.0 + drift, 30e-6);
  EXPECT_EQ(clock.restarts(), 0);
}

TEST(ClockFilterFrames, DeviceRestartResetsTheFilter) {
  ClockFilter clock(camera::FrameClockOptions());
  const std::int64_t host = 1'700'000'000'000'000;
  for (int i = 0; i < 100; ++i) clock.Map(5'000 * kMs + i * 33 * kMs, host + i * 33 * kMs + kMs);
  // The camera restarts: its clock begins again near zero.
  const std::int64_t restart_host = host + 200 * 33 * kMs;
  EXPECT_EQ(clock.Map(10 * kMs, restart_host + kMs), restart_host + kMs);
  EXPECT_EQ(clock.restarts(), 1);
  EXPECT_EQ(clock.Map(43 * kMs, restart_host + 34 * kMs), restart_host + 34 * kMs);
  // A host-side pause of many seconds with a steady device clock is not a reset...
  // ...but a device clock 2 s off the line is.
  clock.Map(76 * kMs + 2'000 * kMs, restart_host + 67 * kMs);
  EXPECT_EQ(clock.restarts(), 2);
}

// ---- Never early (the Wenglor's mapping) --------------------------------------------------------

ClockFilterOptions NeverEarly(double max_drift_ppm) {
  ClockFilterOptions options;
  options.never_early = true;
  options.max_drift = max_drift_ppm * 1e-6;
  options.reset_jump_s = std::numeric_limits<double>::infinity();
  return options;
}

TEST(ClockFilterNeverEarly, FollowsTheLowestLatencyAndNeverPassesTheReceiveTime) {
  ClockFilter mapper(NeverEarly(/*max_drift_ppm=*/100));
  const std::int64_t true_offset = 1'700'000'000'000'000;
  // Latencies: 900, 300, 2000, 50, 700 us; device ticks of 1 ms.
  const std::int64_t latency[] = {900, 300, 2000, 50, 700, 5000, 60};
  for (int k = 0; k < 7; ++k) {
    const std::int64_t device = k * 1000;
    const std::int64_t host = device + true_offset + latency[k];
    const std::int64_t mapped = mapper.Map(device, host);
    EXPECT_LE(mapped, host);
    EXPECT_GE(mapped, device + true_offset);  // the bias is never negative
  }
  // After the 50 us sample the error is 50 us plus at most 100 ppm of the elapsed device time.
  EXPECT_LE(mapper.offset_us() - static_cast<double>(true_offset), 50 + 100e-6 * 3000 + 1);
}

TEST(ClockFilterNeverEarly, TracksASlowDeviceClockWithinTheDriftBound) {
  // The device clock runs 50 ppm slow: host - device grows 50 us per second.
  ClockFilter mapper(NeverEarly(/*max_drift_ppm=*/100));
  double worst = 0;
  for (int k = 0; k < 20000; ++k) {  // 20 s at 1 kHz, constant 100 us latency
    const std::int64_t device = k * 1000;
    const auto host = static_cast<std::int64_t>(static_cast<double>(device) * (1 + 50e-6)) + 100;
    const std::int64_t mapped = mapper.Map(device, host);
    const double truth = static_cast<double>(device) * (1 + 50e-6);
    worst = std::max(worst, std::abs(static_cast<double>(mapped) - truth));
  }
  // Without the drift allowance the error would grow to 1000 us; with it, it stays at the latency.
  EXPECT_LE(worst, 102);
  EXPECT_TRUE(mapper.settled());
  EXPECT_EQ(mapper.drift_ppm(), 0.0);  // never early fits no line
  EXPECT_EQ(mapper.restarts(), 0);
}

}  // namespace
}  // namespace selfcal::timing
