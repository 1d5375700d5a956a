// The clock mapping and scan timing filters on synthetic data with a known truth: a device
// counter with drift and offset, exchanges with latency jitter, a mirror not locked to the
// counter. Simulated time, so minutes of drift take milliseconds to test.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "drivers/hokuyo/clock_filter.h"
#include "drivers/hokuyo/interval_line_fit.h"
#include "drivers/hokuyo/scan_timer.h"

namespace selfcal::hokuyo {
namespace {

TEST(IntervalLineFit, RecoversALineFromIntervalsAtRandomPhases) {
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> phase(0, 1);
  const double a = 12.3456;
  const double b = 1.00005;
  std::vector<IntervalSample> samples;
  for (int i = 0; i < 200; ++i) {
    const double x = i * 10.0 + phase(random);
    const double y = a + b * x;
    const double lo = std::floor(y);  // a quantized reading: y lies in [floor, floor + 1)
    samples.push_back({x, lo, lo + 1});
  }
  const auto fit = FitIntervalLine(samples, 1000.0, 0.999, 1.001);
  EXPECT_TRUE(fit.consistent);
  EXPECT_NEAR(fit.At(1000.0), a + b * 1000.0, 0.02);
  EXPECT_NEAR(fit.slope, b, 5e-6);
  EXPECT_GT(fit.margin, 0);
}

TEST(IntervalLineFit, FewSamplesStayAtThePriorCentre) {
  // Three clustered samples constrain the slope hardly at all: the middle of the prior is kept.
  const std::vector<IntervalSample> samples = {{0, 10, 11}, {0.1, 10, 11}, {0.2, 10.1, 11}};
  const auto fit = FitIntervalLine(samples, 0.2, 0.99, 1.01);
  EXPECT_NEAR(fit.slope, 1.0, 1e-3);
  EXPECT_TRUE(fit.consistent);
}

TEST(IntervalLineFit, InconsistentIntervalsGiveTheMinimaxLine) {
  const std::vector<IntervalSample> samples = {{0, 0, 1}, {1, 3, 4}, {2, 0, 1}};
  const auto fit = FitIntervalLine(samples, 1.0, -1, 1);
  EXPECT_FALSE(fit.consistent);
  EXPECT_LT(fit.margin, 0);
}

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
  ClockFilterOptions options;
  ClockFilter filter(options);
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

TEST(ClockFilter, Follows50PpmDriftWithMillisecondJitter) {
  const ClockRun run = RunClock(50, 1000, 120);
  std::printf(
      "clock filter, 50 ppm drift, 1 ms jitter, 120 s: worst error %.1f us (first 5 s), "
      "%.1f us (after), rate error %.2f ppm\n",
      run.worst_first_5s_us, run.worst_after_5s_us, run.final_rate_error_ppm);
  EXPECT_LT(run.worst_first_5s_us, 350);
  EXPECT_LT(run.worst_after_5s_us, 200);
  EXPECT_LT(std::abs(run.final_rate_error_ppm), 5);
}

TEST(ClockFilter, FollowsLargerDriftToo) {
  const ClockRun run = RunClock(-250, 1000, 60);
  std::printf(
      "clock filter, -250 ppm drift, 1 ms jitter, 60 s: worst error %.1f us (first 5 s), "
      "%.1f us (after)\n",
      run.worst_first_5s_us, run.worst_after_5s_us);
  EXPECT_LT(run.worst_first_5s_us, 350);
  EXPECT_LT(run.worst_after_5s_us, 200);
}

TEST(ClockFilter, WithoutJitterTheBoundIsTight) {
  // The round trip is 100 us: the bound cannot beat half of it.
  const ClockRun run = RunClock(50, 0, 30);
  std::printf("clock filter, 50 ppm drift, no jitter: worst error %.1f us (after 5 s)\n",
              run.worst_after_5s_us);
  EXPECT_LT(run.worst_after_5s_us, 60);
}

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

}  // namespace
}  // namespace selfcal::hokuyo
