// The exchange clock filter on synthetic data with a known truth: a device counter with drift and
// offset, read by request/reply exchanges with latency jitter. Simulated time, so minutes of
// drift take milliseconds to test.
#include "core/timing/exchange_clock_filter.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

namespace selfcal::timing {
namespace {

// A device whose counter runs at (1 + drift) of host time, read by TM1 exchanges with latency
// and jitter: the filter must follow the drift within a small fraction of a millisecond.
struct SyntheticDevice {
  double drift;
  double offset_us;
  double DeviceUs(double host_us) const { return offset_us + host_us * (1 + drift); }
  double HostUs(double device_us) const { return (device_us - offset_us) / (1 + drift); }
};

// The driver's schedule: a burst of 30 exchanges, then one every 20 ms. The command reaches the
// device in 50 us; the reply takes 50 us plus a uniform jitter (the simulator's model).
struct ClockRun {
  double worst_first_5s_us = 0;
  double worst_after_5s_us = 0;
  double final_rate_error_ppm = 0;
};

ClockRun RunClock(double drift_ppm, double jitter_us, double duration_s) {
  const SyntheticDevice device{drift_ppm * 1e-6, 3.21e6};
  ExchangeClockOptions options;
  ExchangeClockFilter filter(options);
  std::mt19937_64 random(11);
  std::uniform_real_distribution<double> uniform(0, 1);
  ClockRun run;
  const double start = 1e6;
  double host = start;
  for (int i = 0; host < start + duration_s * 1e6; ++i) {
    const double send = host;
    const double read_at = send + 50;
    const double receive = read_at + 50 + jitter_us * uniform(random);
    const auto counter = static_cast<std::int64_t>(std::floor(device.DeviceUs(read_at) / 1000));
    filter.AddExchange(send, receive, counter);
    host = receive + (i < 30 ? 300 + 100 * uniform(random) : 20e3);
    if (i >= 30) {
      // Error of mapping a device instant 10 ms ago (what a scan needs).
      const double probe = host - 10e3;
      const double error = std::abs(filter.HostFromDevice(device.DeviceUs(probe)) - probe);
      double& worst = host - start < 5e6 ? run.worst_first_5s_us : run.worst_after_5s_us;
      worst = std::max(worst, error);
    }
  }
  run.final_rate_error_ppm = (filter.rate() - 1 / (1 + drift_ppm * 1e-6)) * 1e6;
  return run;
}

TEST(ExchangeClockFilter, Follows50PpmDriftWithMillisecondJitter) {
  const ClockRun run = RunClock(50, 1000, 120);
  std::printf(
      "clock filter, 50 ppm drift, 1 ms jitter, 120 s: worst error %.1f us (first 5 s), "
      "%.1f us (after), rate error %.2f ppm\n",
      run.worst_first_5s_us, run.worst_after_5s_us, run.final_rate_error_ppm);
  EXPECT_LT(run.worst_first_5s_us, 350);
  EXPECT_LT(run.worst_after_5s_us, 200);
  EXPECT_LT(std::abs(run.final_rate_error_ppm), 5);
}

TEST(ExchangeClockFilter, FollowsLargerDriftToo) {
  const ClockRun run = RunClock(-250, 1000, 60);
  std::printf(
      "clock filter, -250 ppm drift, 1 ms jitter, 60 s: worst error %.1f us (first 5 s), "
      "%.1f us (after)\n",
      run.worst_first_5s_us, run.worst_after_5s_us);
  EXPECT_LT(run.worst_first_5s_us, 350);
  EXPECT_LT(run.worst_after_5s_us, 200);
}

TEST(ExchangeClockFilter, WithoutJitterTheBoundIsTight) {
  // The round trip is 100 us: the bound cannot beat half of it.
  const ClockRun run = RunClock(50, 0, 30);
  std::printf("clock filter, 50 ppm drift, no jitter: worst error %.1f us (after 5 s)\n",
              run.worst_after_5s_us);
  EXPECT_LT(run.worst_after_5s_us, 60);
}

}  // namespace
}  // namespace selfcal::timing
