// The real driver against the SCIP simulator over TCP (127.0.0.1, port 0) and over a pseudo-
// terminal: identification, streaming, per-ray timestamps against the simulator's truth, and
// every fault (the driver recovers or reports, never hangs, never publishes a corrupted scan).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "tests/hokuyo/sim_harness.h"
#include "tools/sim_scip/range_source.h"

namespace selfcal::hokuyo::testing {
namespace {

// Every published value must be exactly what the simulator's pattern put there.
int CountCorrupted(const std::vector<RangeScan>& scans, int start_step = 0) {
  int corrupted = 0;
  for (const RangeScan& scan : scans) {
    const auto ts = static_cast<std::uint32_t>((scan.device_utime / 1000) & 0xFFFFFF);
    for (std::size_t i = 0; i < scan.ranges.size(); ++i) {
      const float expected = static_cast<float>(sim_scip::PatternRangeSource::Range(
                                 start_step + static_cast<int>(i), ts)) *
                             1e-3f;
      if (scan.ranges[i] != expected) {
        ++corrupted;
        break;
      }
    }
  }
  return corrupted;
}

struct TimingErrors {
  double mean_us = 0;
  double worst_us = 0;
  double rms_us = 0;
  int scans = 0;
};

// Error of the first and last ray of each scan whose first ray is at least `after_us` after the
// first scan (the filters need a few seconds of exchanges and scans to lock, docs/hokuyo.md).
TimingErrors MeasureTiming(SimHarness& harness, double after_us) {
  TimingErrors errors;
  const auto scans = harness.Scans();
  if (scans.empty()) return errors;
  double sum = 0;
  int terms = 0;
  for (const RangeScan& scan : scans) {
    if (scan.host_monotonic_us < scans.front().host_monotonic_us + after_us) continue;
    sim_scip::ScanTruth truth;
    const auto ts = static_cast<std::uint32_t>((scan.device_utime / 1000) & 0xFFFFFF);
    if (!harness.Truth(ts, truth)) continue;
    const std::size_t last = scan.ranges.size() - 1;
    for (const std::size_t ray : {std::size_t{0}, last}) {
      const double estimate =
          scan.host_monotonic_us + 1e6 * static_cast<double>(ray) * scan.time_per_ray;
      const double actual =
          truth.timing.host_time_us +
          (truth.timing.first_step + static_cast<double>(ray)) * truth.timing.host_us_per_step;
      const double error = estimate - actual;
      errors.worst_us = std::max(errors.worst_us, std::abs(error));
      sum += error * error;
      errors.mean_us += error;
      ++terms;
    }
    ++errors.scans;
  }
  errors.rms_us = terms ? std::sqrt(sum / terms) : 0;
  errors.mean_us = terms ? errors.mean_us / terms : 0;
  return errors;
}

class DriverSimTest : public ::testing::TestWithParam<Link> {};

TEST_P(DriverSimTest, IdentifiesAndStreamsExactRanges) {
  SimHarness harness(GetParam(), sim_scip::SimDeviceConfig{});
  ASSERT_TRUE(harness.WaitForScans(40, 5.0)) << "scans: " << harness.ScanCount();
  const auto infos = harness.Infos();
  ASSERT_FALSE(infos.empty());
  EXPECT_EQ(infos[0].parameters.model, "UTM-30LX-EW");
  EXPECT_EQ(infos[0].parameters.first_step, 0);
  EXPECT_EQ(infos[0].parameters.last_step, 1080);
  EXPECT_EQ(infos[0].parameters.front_step, 540);
  EXPECT_EQ(infos[0].parameters.steps_per_rotation, 1440);
  EXPECT_EQ(infos[0].parameters.rotation_rpm, 2400);
  EXPECT_EQ(infos[0].version.protocol, "SCIP 2.0");
  EXPECT_EQ(infos[0].version.serial, "H0000001");
  const auto scans = harness.Scans();
  EXPECT_EQ(CountCorrupted(scans), 0);
  for (std::size_t i = 0; i < scans.size(); ++i) {
    ASSERT_EQ(scans[i].ranges.size(), 1081u);
    EXPECT_NEAR(scans[i].angle_first, -135.0 * std::numbers::pi / 180, 1e-12);
    EXPECT_NEAR(scans[i].angle_increment, 0.25 * std::numbers::pi / 180, 1e-12);
    EXPECT_NEAR(scans[i].time_per_ray, 0.025 / 1440, 0.025 / 1440 * 3e-3);
    if (i > 0) {
      EXPECT_EQ(scans[i].scan_counter, scans[i - 1].scan_counter + 1);
    }
  }
  EXPECT_EQ(harness.driver().stats().scans_dropped.load(), 0);
  EXPECT_EQ(harness.driver().stats().sessions.load(), 1);
}

TEST_P(DriverSimTest, PerRayTimestampsWithinHalfAMillisecondUnderDriftAndJitter) {
  sim_scip::SimDeviceConfig device;
  device.clock_drift_ppm = 50;
  device.clock_offset_ms = 987654.321;
  device.latency_us = 200;
  device.latency_jitter_us = 1000;
  device.seed = GetParam() == Link::kTcp ? 3 : 4;
  SimHarness harness(GetParam(), device);
  ASSERT_TRUE(harness.WaitForScans(240, 10.0)) << "scans: " << harness.ScanCount();
  harness.Stop();
  const TimingErrors all = MeasureTiming(harness, 0);
  const TimingErrors settled = MeasureTiming(harness, 3e6);
  std::printf(
      "%s, 50 ppm drift, 1 ms jitter: all %d scans worst %.1f us rms %.1f us; after 3 s "
      "%d scans worst %.1f us rms %.1f us mean %.1f us\n",
      LinkName(GetParam()).c_str(), all.scans, all.worst_us, all.rms_us, settled.scans,
      settled.worst_us, settled.rms_us, settled.mean_us);
  ASSERT_GT(settled.scans, 100);
  EXPECT_LT(settled.worst_us, 500.0);
  EXPECT_EQ(CountCorrupted(harness.Scans()), 0);
}

TEST_P(DriverSimTest, CorruptedScansAreDroppedNotPublished) {
  SimHarness harness(GetParam(), sim_scip::SimDeviceConfig{});
  ASSERT_TRUE(harness.WaitForScans(10, 5.0));
  harness.sim().CorruptNextScans(5);
  harness.sim().InjectJunk("garbage\nFOO\n\n\x01\x02\n\n");
  ASSERT_TRUE(harness.WaitForScans(40, 5.0));
  // 5 corrupted scans and 2 junk blocks, each rejected by its checksum or framing.
  EXPECT_EQ(harness.driver().stats().blocks_rejected.load(), 7);
  EXPECT_EQ(harness.driver().stats().sessions.load(), 1) << "corruption must not reconnect";
  EXPECT_EQ(CountCorrupted(harness.Scans()), 0);
  EXPECT_TRUE(harness.LogsMention("checksum mismatch"));
  // The five lost rotations show as a gap in the counter.
  EXPECT_EQ(harness.driver().stats().lost_scans.load(), 5);
}

TEST_P(DriverSimTest, RecoversFromACablePull) {
  SimHarness harness(GetParam(), sim_scip::SimDeviceConfig{});
  ASSERT_TRUE(harness.WaitForScans(10, 5.0));
  harness.sim().Disconnect(0.5);
  const std::size_t before = harness.ScanCount();
  ASSERT_TRUE(harness.WaitForScans(before + 20, 8.0)) << "scans: " << harness.ScanCount();
  EXPECT_GE(harness.driver().stats().sessions.load(), 2);
  EXPECT_EQ(CountCorrupted(harness.Scans()), 0);
  const auto scans = harness.Scans();
  for (std::size_t i = 1; i < scans.size(); ++i) {
    EXPECT_GT(scans[i].scan_counter, scans[i - 1].scan_counter);
    EXPECT_GT(scans[i].utime, scans[i - 1].utime);
  }
}

TEST_P(DriverSimTest, RecoversFromASensorReboot) {
  sim_scip::SimDeviceConfig device;
  device.clock_offset_ms = 5e6;  // after the reboot the counter starts again at 0
  SimHarness harness(GetParam(), device);
  ASSERT_TRUE(harness.WaitForScans(10, 5.0));
  harness.sim().Reboot(0.7);
  const std::size_t before = harness.ScanCount();
  ASSERT_TRUE(harness.WaitForScans(before + 20, 10.0)) << "scans: " << harness.ScanCount();
  EXPECT_GE(harness.driver().stats().sessions.load(), 2);
  EXPECT_EQ(CountCorrupted(harness.Scans()), 0);
  const auto scans = harness.Scans();
  EXPECT_GT(scans.front().device_utime, 4'000'000'000);
  EXPECT_LT(scans.back().device_utime, 100'000'000);  // the rebooted counter
  for (std::size_t i = 1; i < scans.size(); ++i) {
    EXPECT_GT(scans[i].scan_counter, scans[i - 1].scan_counter);
    EXPECT_GT(scans[i].utime, scans[i - 1].utime);
  }
}

TEST_P(DriverSimTest, ReportsAndRecoversFromAStalledStream) {
  SimHarness harness(GetParam(), sim_scip::SimDeviceConfig{});
  ASSERT_TRUE(harness.WaitForScans(10, 5.0));
  harness.sim().Stall(2.0);
  const std::size_t before = harness.ScanCount();
  ASSERT_TRUE(harness.WaitForScans(before + 20, 8.0)) << "scans: " << harness.ScanCount();
  EXPECT_TRUE(harness.LogsMention("stream stalled"));
  EXPECT_GE(harness.driver().stats().sessions.load(), 2);
  EXPECT_EQ(CountCorrupted(harness.Scans()), 0);
}

TEST_P(DriverSimTest, CountsAcrossTheCounterWrap) {
  sim_scip::SimDeviceConfig device;
  device.clock_offset_ms = 16777216.0 - 1500;  // the 24-bit counter wraps 1.5 s in
  SimHarness harness(GetParam(), device);
  ASSERT_TRUE(harness.WaitForScans(100, 8.0));
  const auto scans = harness.Scans();
  EXPECT_EQ(CountCorrupted(scans), 0);
  for (std::size_t i = 1; i < scans.size(); ++i) {
    EXPECT_EQ(scans[i].scan_counter, scans[i - 1].scan_counter + 1);
    EXPECT_NEAR(static_cast<double>(scans[i].device_utime - scans[i - 1].device_utime), 25025,
                1000);
  }
  EXPECT_GT(scans.back().device_utime, 16777216LL * 1000);
  EXPECT_EQ(harness.driver().stats().sessions.load(), 1);
}

TEST_P(DriverSimTest, IntensitiesWithMeAndAPartialRange) {
  HokuyoConfig config;
  config.scan_type = scip::ScanType::kME;
  config.start_step = 100;
  config.end_step = 299;
  SimHarness harness(GetParam(), sim_scip::SimDeviceConfig{}, config);
  ASSERT_TRUE(harness.WaitForScans(10, 5.0));
  const auto scans = harness.Scans();
  EXPECT_EQ(CountCorrupted(scans, 100), 0);
  for (const auto& scan : scans) {
    ASSERT_EQ(scan.ranges.size(), 200u);
    ASSERT_EQ(scan.intensities.size(), 200u);
    EXPECT_EQ(scan.intensities[0], 1100.0f);
    EXPECT_EQ(scan.intensities[199], 1299.0f);
    EXPECT_NEAR(scan.angle_first, (100 - 540) * 2 * std::numbers::pi / 1440, 1e-12);
  }
}

INSTANTIATE_TEST_SUITE_P(Links, DriverSimTest, ::testing::Values(Link::kTcp, Link::kPty),
                         [](const auto& info) { return LinkName(info.param); });

TEST(DriverSerial, DetectsTheBitRateAndSwitchesWithSs) {
  sim_scip::SimDeviceConfig device;
  device.serial_baud = 57600;  // an RS-232 URG set to 57600: the driver must find it
  HokuyoConfig config;
  config.target_baud = 115200;
  SimHarness harness(Link::kPty, device, config);
  ASSERT_TRUE(harness.WaitForScans(10, 10.0)) << "scans: " << harness.ScanCount();
  const auto infos = harness.Infos();
  ASSERT_FALSE(infos.empty());
  EXPECT_EQ(infos[0].baud, 115200);
  EXPECT_EQ(CountCorrupted(harness.Scans()), 0);
}

TEST(DriverNoDevice, RetriesWithBackoffAndStopsPromptly) {
  // A port nobody listens on: bind one, learn its number, close it.
  int port = 0;
  {
    auto sim = sim_scip::SimServer::Start({}, {});
    ASSERT_TRUE(sim.ok());
    port = (*sim)->port();
  }
  HokuyoConfig config;
  config.host = "127.0.0.1";
  config.port = port;
  config.backoff_initial_s = 0.05;
  config.backoff_max_s = 0.2;
  std::vector<std::string> logs;
  std::mutex mutex;
  HokuyoDriver driver(
      config, [](const RangeScan&) { FAIL() << "no scans expected"; },
      [&](LogLevel, const std::string& m) {
        std::lock_guard<std::mutex> lock(mutex);
        logs.push_back(m);
      });
  std::atomic<bool> stop{false};
  std::thread thread([&] { driver.Run(stop); });
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  const auto begin = std::chrono::steady_clock::now();
  stop.store(true);
  thread.join();
  EXPECT_LT(std::chrono::steady_clock::now() - begin, std::chrono::milliseconds(500));
  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_GE(logs.size(), 3u);
  EXPECT_NE(logs[0].find("connect failed"), std::string::npos) << logs[0];
  EXPECT_NE(logs[0].find("Connection refused"), std::string::npos) << logs[0];
}

TEST(DriverConfig, ValidateNamesTheProblem) {
  HokuyoConfig config;
  EXPECT_FALSE(HokuyoDriver::Validate(config).ok());  // no device
  config.device = "/dev/ttyACM0";
  EXPECT_TRUE(HokuyoDriver::Validate(config).ok());
  config.host = "192.168.0.10";
  EXPECT_FALSE(HokuyoDriver::Validate(config).ok());
  config.host.clear();
  config.baud = 12345;
  EXPECT_FALSE(HokuyoDriver::Validate(config).ok());
  config.baud = 0;
  config.scan_type = scip::ScanType::kGD;
  EXPECT_FALSE(HokuyoDriver::Validate(config).ok());
}

}  // namespace
}  // namespace selfcal::hokuyo::testing
