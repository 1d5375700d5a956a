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

TEST_P(DriverSimTest, StreamsWithoutTm1WhileStreamingAtSyncIntervalZero) {
  HokuyoConfig config;
  config.sync_interval_s = 0;  // the fallback for sensors that refuse TM1 while streaming
  SimHarness harness(GetParam(), sim_scip::SimDeviceConfig{}, config);
  ASSERT_TRUE(harness.WaitForScans(40, 5.0)) << "scans: " << harness.ScanCount();
  EXPECT_EQ(harness.driver().stats().sessions.load(), 1);
  // The initial burst only.
  EXPECT_EQ(harness.driver().stats().clock_exchanges.load(), config.sync_exchanges);
  EXPECT_FALSE(harness.LogsMention("stream stalled"));
  EXPECT_EQ(CountCorrupted(harness.Scans()), 0);
}

// The index of the first scan of the second session: the largest gap in device time.
std::size_t FirstAfterOutage(const std::vector<RangeScan>& scans) {
  std::size_t at = 1;
  for (std::size_t i = 1; i < scans.size(); ++i) {
    if (scans[i].host_monotonic_us - scans[i - 1].host_monotonic_us >
        scans[at].host_monotonic_us - scans[at - 1].host_monotonic_us) {
      at = i;
    }
  }
  return at;
}

TEST_P(DriverSimTest, TheCounterCountsTheRotationsOfAnOutage) {
  SimHarness harness(GetParam(), sim_scip::SimDeviceConfig{});
  ASSERT_TRUE(harness.WaitForScans(10, 5.0));
  harness.sim().Disconnect(1.0);
  const std::size_t before = harness.ScanCount();
  ASSERT_TRUE(harness.WaitForScans(before + 20, 8.0)) << "scans: " << harness.ScanCount();
  harness.Stop();
  EXPECT_EQ(harness.driver().stats().sessions.load(), 2);
  const auto scans = harness.Scans();
  const std::size_t after = FirstAfterOutage(scans);
  // The device clock ran on through the outage: its time stamps say how many rotations passed
  // (25.025 ms each, a time stamp floors to the ms).
  const double device_gap_us =
      static_cast<double>(scans[after].device_utime - scans[after - 1].device_utime);
  const std::int64_t rotations = std::llround(device_gap_us / 25025.0);
  std::printf("%s: outage of %.3f s, %lld rotations; counter %lld -> %lld, lost_scans %lld\n",
              LinkName(GetParam()).c_str(), device_gap_us * 1e-6, static_cast<long long>(rotations),
              static_cast<long long>(scans[after - 1].scan_counter),
              static_cast<long long>(scans[after].scan_counter),
              static_cast<long long>(harness.driver().stats().lost_scans.load()));
  EXPECT_GT(rotations, 40);  // at least the second the link was down
  EXPECT_EQ(scans[after].scan_counter - scans[after - 1].scan_counter, rotations);
  std::int64_t gaps = 0;
  for (std::size_t i = 1; i < scans.size(); ++i) {
    gaps += scans[i].scan_counter - scans[i - 1].scan_counter - 1;
  }
  EXPECT_EQ(harness.driver().stats().lost_scans.load(), gaps);
  EXPECT_GE(gaps, rotations - 1);
}

TEST_P(DriverSimTest, StreamsSoonAfterABootingSensorStopsDenyingTm0) {
  sim_scip::SimDeviceConfig device;
  device.answers_while_booting = true;  // a UTM: connects at once, denies TM0 until booted
  device.clock_offset_ms = 5e6;         // scans after the reboot have a counter near 0
  // The driver's own backoff (0.1 s doubling to 5 s), not the harness's short one.
  SimHarness harness(GetParam(), device, HokuyoConfig{}, /*short_backoff=*/false);
  ASSERT_TRUE(harness.WaitForScans(10, 5.0));
  constexpr double kBootS = 2.0;
  const auto reboot = std::chrono::steady_clock::now();
  harness.sim().Reboot(kBootS);
  double restart_s = -1;
  while (std::chrono::steady_clock::now() - reboot < std::chrono::seconds(10)) {
    const auto scans = harness.Scans();
    if (scans.back().device_utime < 1'000'000'000) {
      restart_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - reboot).count();
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  std::printf("%s: reboot of %.1f s, first scan %.3f s after the restart\n",
              LinkName(GetParam()).c_str(), kBootS, restart_s);
  ASSERT_GT(restart_s, kBootS) << "the simulator denied TM0 while booting";
  EXPECT_LT(restart_s, kBootS + 0.6);
  EXPECT_TRUE(harness.LogsMention("TM0 answered 10"));
  ASSERT_TRUE(harness.WaitForScans(harness.ScanCount() + 5, 5.0));
  harness.Stop();
  // The device clock restarted: the host times of the two scans around the reboot give the
  // rotations that passed.
  const auto scans = harness.Scans();
  const std::size_t after = FirstAfterOutage(scans);
  sim_scip::ScanTruth old_truth, new_truth;
  ASSERT_TRUE(harness.Truth(
      static_cast<std::uint32_t>((scans[after - 1].device_utime / 1000) & 0xFFFFFF), old_truth));
  ASSERT_TRUE(harness.Truth(
      static_cast<std::uint32_t>((scans[after].device_utime / 1000) & 0xFFFFFF), new_truth));
  const std::int64_t rotations =
      std::llround((new_truth.timing.host_time_us - old_truth.timing.host_time_us) / 25025.0);
  EXPECT_EQ(scans[after].scan_counter - scans[after - 1].scan_counter, rotations);
}

// Every log line names the link it is about once, whichever layer wrote the error.
int Occurrences(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST_P(DriverSimTest, LogLinesNameTheLinkOnce) {
  SimHarness harness(GetParam(), sim_scip::SimDeviceConfig{});
  ASSERT_TRUE(harness.WaitForScans(10, 5.0));
  harness.sim().Stall(2.5);  // stalled stream, then QT unanswered, then back
  const std::size_t before = harness.ScanCount();
  ASSERT_TRUE(harness.WaitForScans(before + 10, 10.0)) << "scans: " << harness.ScanCount();
  harness.Stop();
  const std::string link = GetParam() == Link::kTcp
                               ? "tcp://127.0.0.1:" + std::to_string(harness.sim().port())
                               : harness.config().device;
  bool no_reply = false;
  for (const std::string& line : harness.Logs()) {
    EXPECT_LE(Occurrences(line, link), 1) << line;
    if (line.find("no reply to QT") != std::string::npos) {
      no_reply = true;
      EXPECT_EQ(line.rfind(link + ": no reply to QT", 0), 0u) << line;
    }
  }
  // Over the pty the stalled sensor answers no probe, so the driver never gets to send QT.
  if (GetParam() == Link::kTcp) {
    EXPECT_TRUE(no_reply);
  }
  EXPECT_TRUE(harness.LogsMention(link + ": stream stalled"));
}

TEST_P(DriverSimTest, AFloodOfJunkIsLoggedAFewTimesAndCounted) {
  SimHarness harness(GetParam(), sim_scip::SimDeviceConfig{});
  ASSERT_TRUE(harness.WaitForScans(10, 5.0));
  harness.sim().InjectJunk(std::string(1'000'000, 'A'));  // 1 MB without a newline
  const std::size_t before = harness.ScanCount();
  ASSERT_TRUE(harness.WaitForScans(before + 20, 8.0)) << "scans: " << harness.ScanCount();
  harness.Stop();
  const std::string link = GetParam() == Link::kTcp
                               ? "tcp://127.0.0.1:" + std::to_string(harness.sim().port())
                               : harness.config().device;
  int passed = 0;
  long long suppressed = -1;
  for (const std::string& line : harness.Logs()) {
    if (line.rfind("rejected block: ", 0) == 0) suppressed = std::stoll(line.substr(16));
    if (line.rfind(link + ": byte ", 0) == 0) ++passed;
  }
  const auto rejected = harness.driver().stats().blocks_rejected.load();
  std::printf("%s: %lld blocks rejected, %d logged, %lld counted in a summary\n",
              LinkName(GetParam()).c_str(), static_cast<long long>(rejected), passed, suppressed);
  EXPECT_GE(rejected, 10);  // 1 MB in blocks of at most 64 kB
  EXPECT_LE(passed, 5);
  EXPECT_EQ(passed + suppressed, rejected) << "every rejection is logged or counted";
  EXPECT_EQ(harness.driver().stats().sessions.load(), 1);
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
  config.scan_type = scip::ScanType::kMD;
  config.sync_interval_s = 0;  // no TM1 while streaming
  EXPECT_TRUE(HokuyoDriver::Validate(config).ok());
  config.sync_interval_s = -0.02;
  const auto negative = HokuyoDriver::Validate(config);
  ASSERT_FALSE(negative.ok());
  EXPECT_NE(negative.error().message.find("sync_interval_s"), std::string::npos);
  config.sync_interval_s = std::nan("");
  EXPECT_FALSE(HokuyoDriver::Validate(config).ok());
}

}  // namespace
}  // namespace selfcal::hokuyo::testing
