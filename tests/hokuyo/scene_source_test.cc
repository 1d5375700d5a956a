// The simulator serving ranges computed by core/sim for a scenario's scene and robot, with joint
// states arriving over LCM (memq://): the real driver must publish exactly the ranges the ray
// caster gives for the robot's pose at each ray's time.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "core/model/kinematics.h"
#include "protocols/lcm/channels.h"
#include "selfcal/joint_state_t.hpp"
#include "selfcal/scan_marker_t.hpp"
#include "tests/hokuyo/sim_harness.h"
#include "tests/time_scale.h"
#include "tools/sim_scip/joint_state_feed.h"
#include "tools/sim_scip/scene_range_source.h"

namespace selfcal::sim_scip {
namespace {

std::string Scenario() {
  return std::string(std::getenv("SELFCAL_SOURCE_DIR")) + "/config/scenarios/hokuyo-office.yaml";
}

// A pose of the iiwa with the sensor looking into the corner scene.
const std::vector<double> kPoseA = {0.3, 0.6, 0.0, -1.2, 0.0, 0.9, 0.0};
const std::vector<double> kPoseB = {0.5, 0.5, 0.1, -1.0, 0.2, 1.1, 0.3};

std::string FieldScenario() {
  return std::string(std::getenv("SELFCAL_SOURCE_DIR")) +
         "/config/scenarios/field/hokuyo-office.yaml";
}

// The field twin with some of its text replaced, written as `name` into the test's folder.
std::string FieldScenarioWith(const std::vector<std::pair<std::string, std::string>>& changes,
                              const std::string& name) {
  const std::string root = std::getenv("SELFCAL_SOURCE_DIR");
  std::ifstream in(FieldScenario());
  std::stringstream text;
  text << in.rdbuf();
  std::string changed = text.str();
  auto replace = [&](const std::string& from, const std::string& to) {
    const std::size_t at = changed.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) changed.replace(at, from.size(), to);
  };
  replace("../../robots/", root + "/config/robots/");
  replace("../../sensors/", root + "/config/sensors/");
  for (const auto& [from, to] : changes) replace(from, to);
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path) << changed;
  return path;
}

// A whole rotation of the UTM-30LX long after its warm-up, begun at `start_us` (host time).
ScanTiming Rotation(double start_us) {
  ScanTiming timing;
  timing.timestamp_ms = 1500;
  timing.device_time_us = 1.5e9;
  timing.last_step = 1080;
  timing.front_step = 540;
  timing.steps_per_rotation = 1440;
  timing.host_us_per_step = 25000.0 / 1440;
  timing.host_time_us = start_us;
  return timing;
}

std::vector<std::uint32_t> RangesOf(SceneRangeSource& source, double start_us) {
  std::vector<std::uint32_t> ranges(1081), intensities(1081);
  source.Ranges(Rotation(start_us), ranges, intensities);
  return ranges;
}

// The median range [m] of the eleven rays around the front (the noise and an edge aside).
double FrontRange(SceneRangeSource& source, double start_us) {
  const std::vector<std::uint32_t> ranges = RangesOf(source, start_us);
  std::vector<std::uint32_t> front(ranges.begin() + 535, ranges.begin() + 546);
  std::nth_element(front.begin(), front.begin() + 5, front.end());
  return front[5] * 1e-3;
}

std::string Vector(const Eigen::Vector3d& v) {
  std::ostringstream out;
  out.precision(17);
  out << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
  return out.str();
}

TEST(SceneRangeSource, InterpolatesJointsToEachRayTime) {
  auto source = SceneRangeSource::Create(Scenario());
  ASSERT_TRUE(source.ok()) << source.error().message;
  ASSERT_EQ((*source)->joint_names().size(), 7u);
  (*source)->AddJointState(1e6, kPoseA);
  (*source)->AddJointState(2e6, kPoseB);
  ScanTiming timing;
  timing.first_step = 0;
  timing.last_step = 1080;
  timing.front_step = 540;
  timing.steps_per_rotation = 1440;
  timing.host_us_per_step = 25000.0 / 1440;
  timing.host_time_us = 1.5e6 - 540 * timing.host_us_per_step;  // the front ray at 1.5 s
  std::vector<std::uint32_t> ranges(1081), intensities(1081);
  (*source)->Ranges(timing, ranges, intensities);
  std::vector<double> middle(7);
  for (std::size_t j = 0; j < 7; ++j) middle[j] = 0.5 * (kPoseA[j] + kPoseB[j]);
  const double front = (*source)->RangeAt(middle, 0.0);
  ASSERT_TRUE(std::isfinite(front)) << "the front ray should hit the scene";
  EXPECT_EQ(ranges[540], static_cast<std::uint32_t>(std::round(front * 1000)));
  int hits = 0;
  for (const auto r : ranges) hits += r >= 23 ? 1 : 0;
  EXPECT_GT(hits, 500);
  // A different pose gives different ranges: the robot's motion is what the sensor sees.
  EXPECT_NE(std::round((*source)->RangeAt(kPoseA, 0.0) * 1000), std::round(front * 1000));
}

// The field twin serves the sensor file's noise and the field effects: ranges scatter around
// the ideal ray casts with about the Hokuyo's 18 mm (more at oblique incidence, plus a few mm of
// bias), the same request gives the same ranges, and the ideal scenario stays exact.
TEST(SceneRangeSource, FieldScenarioServesNoiseAndEffects) {
  auto field = SceneRangeSource::Create(FieldScenario());
  ASSERT_TRUE(field.ok()) << field.error().message;
  (*field)->AddJointState(1e6, kPoseA);
  (*field)->AddJointState(2e6, kPoseA);
  const std::vector<std::uint32_t> ranges = RangesOf(**field, 1.5e6);
  EXPECT_EQ(ranges, RangesOf(**field, 1.5e6));
  double sum = 0, squares = 0;
  int count = 0;
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    const double angle = 2 * std::numbers::pi * (static_cast<double>(i) - 540) / 1440;
    const double ideal = (*field)->RangeAt(kPoseA, angle);
    if (ranges[i] <= 1 || !std::isfinite(ideal) || ideal > 10) continue;
    const double difference = ranges[i] * 1e-3 - ideal;
    if (std::abs(difference) > 0.2) continue;  // a mixed pixel at an edge, or the arm itself
    sum += difference;
    squares += difference * difference;
    ++count;
  }
  ASSERT_GT(count, 500);
  const double mean = sum / count;
  const double sigma = std::sqrt(squares / count - mean * mean);
  EXPECT_GT(mean, 0.0);  // 5 mm offset, 10 mm (1 - cos i), 0.2 % and 5 mm of intrinsics
  EXPECT_LT(mean, 0.04);
  EXPECT_GT(sigma, 0.015);  // 18 mm, times 1 / cos i on oblique surfaces
  EXPECT_LT(sigma, 0.06);
}

// The field twin with its office painted near-black: returns are lost on the dark surfaces and
// those that remain read longer by the reflectivity bias, as `selfcal simulate` measures them.
TEST(SceneRangeSource, DarkSurfacesLoseReturnsAndReadLonger) {
  const std::string path = FieldScenarioWith(
      {{"albedo: {furniture: 0.15, room: 0.8}", "albedo: {furniture: 0.001, room: 0.001}"}},
      "hokuyo-office-dark.yaml");
  auto light = SceneRangeSource::Create(FieldScenario());
  auto black = SceneRangeSource::Create(path);
  ASSERT_TRUE(light.ok()) << light.error().message;
  ASSERT_TRUE(black.ok()) << black.error().message;
  for (auto* source : {&*light, &*black}) {
    (*source)->AddJointState(1e6, kPoseA);
    (*source)->AddJointState(2e6, kPoseA);
  }
  const std::vector<std::uint32_t> a = RangesOf(**light, 1.5e6);
  const std::vector<std::uint32_t> b = RangesOf(**black, 1.5e6);
  int light_returns = 0, dark_returns = 0, both = 0;
  double longer = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    light_returns += a[i] > 1 ? 1 : 0;
    dark_returns += b[i] > 1 ? 1 : 0;
    // The same noise on both: the difference is the bias (mixed pixels aside).
    if (a[i] > 1 && b[i] > 1 && std::abs(static_cast<double>(b[i]) - a[i]) < 20) {
      longer += static_cast<double>(b[i]) - a[i];
      ++both;
    }
  }
  ASSERT_GT(light_returns, 500);
  EXPECT_LT(dark_returns, light_returns / 2);  // s = 0.001 cos i / r^2 against 0.001
  ASSERT_GT(both, 50);
  // 10 mm (1 - 0.001) on a black surface against 2 mm (walls) to 8.5 mm (furniture).
  EXPECT_GT(longer / both, 1.0);
  EXPECT_LT(longer / both, 9.0);
}

// A person walks through scan 3 across the front ray (which points down at the floor 1.36 m out),
// a box 0.95 m out is moved aside before scan 5: what the front ray reads follows the scan markers,
// the first over the bus.
TEST(SceneRangeSource, TheWalkerAndTheMovedBoxFollowTheScanMarkers) {
  auto plain = SceneRangeSource::Create(FieldScenario());
  ASSERT_TRUE(plain.ok()) << plain.error().message;
  const RobotModel& truth = (*plain)->truth();
  const Eigen::Isometry3d T = ForwardKinematics<double, double>(
      JointTypes(truth), ToParameterVector(truth).data(), kPoseA.data());
  const Eigen::Vector3d ahead = T.linear().col(0);  // the front ray (angle 0)
  const Eigen::Vector3d aside = Eigen::Vector3d(-ahead.y(), ahead.x(), 0).normalized() * 3;
  // The person's axis 0.45 m out on the level, on the ray: the ray meets the 0.25 m capsule
  // 0.2 m out on the level.
  const double level = Eigen::Vector3d(ahead.x(), ahead.y(), 0).norm();
  const Eigen::Vector3d person =
      T.translation() + 0.45 / level * ahead - Eigen::Vector3d(0, 0, 1.5);
  const Eigen::Vector3d box = T.translation() + 0.95 * ahead - Eigen::Vector3d(0, 0, 0.5);
  ASSERT_GT((*plain)->RangeAt(kPoseA, 0.0), 1.3) << "the scene behind them";
  const std::string path = FieldScenarioWith(
      {{"walker: {scans: [5, 12, 19, 26, 31], from: [2.5, -1.0, -0.8], to: [2.5, 1.3, -0.8]}",
        "walker: {scans: [3], from: " + Vector(person) + ", to: " + Vector(person + aside) +
            ", height: 3.0}"},
       {"moved_object: {after_scan: 14, size: [0.3, 0.25, 0.3], position: [3.0, 0.5, -0.05], "
        "shift: [0.0, 0.3, 0.0]}",
        "moved_object: {after_scan: 5, size: [0.2, 0.2, 1.0], position: " + Vector(box) +
            ", shift: " + Vector(aside) + "}"}},
      "hokuyo-office-movers.yaml");
  auto created = SceneRangeSource::Create(path);
  ASSERT_TRUE(created.ok()) << created.error().message;
  SceneRangeSource& source = **created;
  auto bus = OpenLcmBus("memq://");
  ASSERT_TRUE(bus.ok());
  FeedScanMarkers(**bus, channels::kScanMarker, source);
  const double now_us = static_cast<double>(std::chrono::duration_cast<std::chrono::microseconds>(
                                                std::chrono::steady_clock::now().time_since_epoch())
                                                .count());
  source.AddJointState(now_us - 1e6, kPoseA);
  source.AddJointState(now_us, kPoseA);

  const double box_face = 0.95 - 0.1 / std::max(std::abs(ahead.x()), std::abs(ahead.y()));
  EXPECT_NEAR(FrontRange(source, now_us - 0.5e6), box_face, 0.1) << "before any scan: the box";
  scan_marker_t begin;
  begin.utime = std::chrono::duration_cast<std::chrono::microseconds>(
                    std::chrono::system_clock::now().time_since_epoch())
                    .count();
  begin.event = scan_marker_t::BEGIN;
  begin.purpose = scan_marker_t::FIT;
  begin.scan_index = 3;
  ASSERT_TRUE((*bus)->Publish(channels::kScanMarker, begin).ok());
  while (*(*bus)->HandleOnce(std::chrono::milliseconds(0))) {
  }
  const double walker = FrontRange(source, now_us + 0.1e6);
  EXPECT_NEAR(walker, 0.2 / level, 0.05) << "scan 3 has just begun: the person stands in front";
  EXPECT_NEAR(FrontRange(source, now_us + 60e6), box_face, 0.1) << "the walk is over";
  source.AddScanMarker(now_us + 70e6, 5, true);
  EXPECT_GT(FrontRange(source, now_us + 70.5e6), 1.2) << "scan 5: the box was moved aside";
}

// The arm lags the joint states by half its play after they rose: the rays are cast from where a
// stream standing there puts them, with the same noise.
TEST(SceneRangeSource, BacklashLeavesTheArmHalfItsPlayBehind) {
  const double play = 2.0e-4;  // the twin's backlash angle
  std::vector<double> behind = kPoseA, below = kPoseA;
  for (double& q : behind) q -= 0.5 * play;
  for (double& q : below) q -= 1e-3;
  std::vector<std::unique_ptr<SceneRangeSource>> sources;
  for (int k = 0; k < 3; ++k) {
    auto source = SceneRangeSource::Create(FieldScenario());
    ASSERT_TRUE(source.ok()) << source.error().message;
    sources.push_back(std::move(*source));
  }
  sources[0]->AddJointState(0.5e6, below);  // rises to A
  for (double t : {1e6, 2e6}) {
    sources[0]->AddJointState(t, kPoseA);
    sources[1]->AddJointState(t, behind);
    sources[2]->AddJointState(t, kPoseA);
  }
  const std::vector<std::uint32_t> risen = RangesOf(*sources[0], 1.4e6);
  EXPECT_EQ(risen, RangesOf(*sources[1], 1.4e6));
  EXPECT_NE(risen, RangesOf(*sources[2], 1.4e6)) << "the play must move some ray";
}

// A ray stamped s is measured at s + latency from where the joint states say the arm was at
// s + latency + joint_lag: the twin with 15.625 ms and 7.8125 ms serves at s what the same twin
// without them serves at s + 23.4375 ms. Its clock drift is the device's.
TEST(SceneRangeSource, LatencyAndLaggingJointStatesShiftWhereTheRaysAreCast) {
  auto lagged = SceneRangeSource::Create(
      FieldScenarioWith({{"sensor_latency: 0.02", "sensor_latency: 0.015625"},
                         {"timing: {joint_lag: 0.003,", "timing: {joint_lag: 0.0078125,"}},
                        "hokuyo-office-lagged.yaml"));
  auto prompt = SceneRangeSource::Create(
      FieldScenarioWith({{"sensor_latency: 0.02", "sensor_latency: 0.0"},
                         {"timing: {joint_lag: 0.003,", "timing: {joint_lag: 0.0,"}},
                        "hokuyo-office-prompt.yaml"));
  ASSERT_TRUE(lagged.ok()) << lagged.error().message;
  ASSERT_TRUE(prompt.ok()) << prompt.error().message;
  for (auto* source : {&*lagged, &*prompt}) {
    (*source)->AddJointState(1e6, kPoseA);
    (*source)->AddJointState(2e6, kPoseB);
  }
  const std::vector<std::uint32_t> ranges = RangesOf(**lagged, 1.4e6);
  EXPECT_EQ(ranges, RangesOf(**prompt, 1.4e6 + 23437.5));
  EXPECT_NE(ranges, RangesOf(**prompt, 1.4e6));
  EXPECT_EQ((*lagged)->ClockDriftPpm(), 20.0);
  auto ideal = SceneRangeSource::Create(Scenario());
  ASSERT_TRUE(ideal.ok()) << ideal.error().message;
  EXPECT_EQ((*ideal)->ClockDriftPpm(), 0.0);
}

TEST(SceneRangeSource, ExtrapolatesPastTheNewestJointStateForFiftyMilliseconds) {
  auto source = SceneRangeSource::Create(Scenario());
  ASSERT_TRUE(source.ok()) << source.error().message;
  std::vector<double> step = kPoseA;
  for (double& q : step) q += 0.001;
  (*source)->AddJointState(1.00e6, kPoseA);
  (*source)->AddJointState(1.01e6, step);  // 0.1 rad/s on every joint
  std::vector<double> expected = step;
  for (double& q : expected) q += 0.001;  // 10 ms later at the same speed
  ScanTiming timing;
  timing.first_step = timing.last_step = timing.front_step = 540;
  timing.steps_per_rotation = 1440;
  timing.host_us_per_step = 25000.0 / 1440;
  std::vector<std::uint32_t> ranges(1), intensities(1);
  timing.host_time_us = 1.02e6 - 540 * timing.host_us_per_step;
  (*source)->Ranges(timing, ranges, intensities);
  EXPECT_EQ(ranges[0],
            static_cast<std::uint32_t>(std::round((*source)->RangeAt(expected, 0.0) * 1000)));
  timing.host_time_us = 1.2e6 - 540 * timing.host_us_per_step;  // 190 ms past: held
  (*source)->Ranges(timing, ranges, intensities);
  EXPECT_EQ(ranges[0],
            static_cast<std::uint32_t>(std::round((*source)->RangeAt(step, 0.0) * 1000)));
}

TEST(SceneRangeSource, DriverPublishesTheRayCastRangesWithJointStatesOverLcm) {
  auto created = SceneRangeSource::Create(Scenario());
  ASSERT_TRUE(created.ok()) << created.error().message;
  std::shared_ptr<SceneRangeSource> source = std::move(*created);
  auto bus = OpenLcmBus("memq://");
  ASSERT_TRUE(bus.ok());
  std::int64_t rejected = 0;
  FeedJointStates(**bus, channels::kJointState, *source, &rejected);
  // The robot stands still at pose A: joint states at 200 Hz for the whole run, by name.
  joint_state_t state;
  state.num_joints = 7;
  state.names = source->joint_names();
  state.positions = kPoseA;
  state.velocities.assign(7, 0.0);
  state.efforts.assign(7, std::nan(""));
  state.device_utime = -1;
  auto publish_state = [&] {
    state.utime = std::chrono::duration_cast<std::chrono::microseconds>(
                      std::chrono::system_clock::now().time_since_epoch())
                      .count();
    ASSERT_TRUE((*bus)->Publish(channels::kJointState, state).ok());
    while (*(*bus)->HandleOnce(std::chrono::milliseconds(0))) {
    }
  };
  publish_state();

  sim_scip::SimServerOptions options;
  auto sim = SimServer::Start(SimDeviceConfig{}, options, source);
  ASSERT_TRUE(sim.ok()) << sim.error().message;
  hokuyo::HokuyoConfig config;
  config.host = "127.0.0.1";
  config.port = (*sim)->port();
  std::mutex mutex;
  std::vector<hokuyo::RangeScan> scans;
  hokuyo::HokuyoDriver driver(config, [&](const hokuyo::RangeScan& scan) {
    std::lock_guard<std::mutex> lock(mutex);
    scans.push_back(scan);
  });
  std::atomic<bool> stop{false};
  std::thread thread([&] { driver.Run(stop); });
  const auto until = std::chrono::steady_clock::now() + testing::Scaled(std::chrono::seconds(5));
  while (std::chrono::steady_clock::now() < until) {
    publish_state();
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    std::lock_guard<std::mutex> lock(mutex);
    if (scans.size() >= 10) break;
  }
  stop.store(true);
  thread.join();
  (*sim)->Stop();
  EXPECT_EQ(rejected, 0);
  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_GE(scans.size(), 10u);
  int compared = 0;
  for (const auto& scan : scans) {
    for (std::size_t i = 0; i < scan.ranges.size(); i += 20) {
      const double angle = scan.angle_first + static_cast<double>(i) * scan.angle_increment;
      const double expected = source->RangeAt(kPoseA, angle);
      if (!std::isfinite(expected) || expected < 0.023 || expected > 60) {
        EXPECT_TRUE(std::isnan(scan.ranges[i])) << "ray " << i;
      } else {
        EXPECT_NEAR(scan.ranges[i], expected, 0.0006) << "ray " << i;
        ++compared;
      }
    }
  }
  EXPECT_GT(compared, 200);
}

}  // namespace
}  // namespace selfcal::sim_scip
