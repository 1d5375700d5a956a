// Sensor noise statistics: the simulator's measurements of known surfaces have the mean and
// the standard deviation of the paper's noise models (Table I), and gaps are NaN.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/sim/ray_caster.h"
#include "core/sim/simulator.h"
#include "tests/sim/small_world.h"

namespace selfcal::sim {
namespace {

using small_world::PointRobot;
using small_world::StillPlan;

struct Stats {
  double mean = 0, sigma = 0;
  std::size_t count = 0, nans = 0;
};

Stats Measure(const std::vector<double>& values, std::size_t nans) {
  Stats s;
  s.count = values.size();
  s.nans = nans;
  for (double v : values) s.mean += v;
  s.mean /= static_cast<double>(values.size());
  for (double v : values) s.sigma += (v - s.mean) * (v - s.mean);
  s.sigma = std::sqrt(s.sigma / static_cast<double>(values.size() - 1));
  return s;
}

SensorModel Kinect() {
  SensorModel m;
  m.kind = SensorLayout::kDepthCamera;
  m.width = 320;
  m.height = 288;
  m.range_min = 0.5;
  m.range_max = 5.46;
  m.sigma_abs = 0.00253;
  m.sigma_rel = 0.0021;
  m.intrinsics.fx = 208.5;
  m.intrinsics.fy = 226.0;
  m.intrinsics.cx = 159.5;
  m.intrinsics.cy = 143.5;
  m.frame_period = 1.0 / 30;
  return m;
}

void ExpectGaussian(const Stats& s, double mean, double sigma) {
  ASSERT_GT(s.count, 10000u);
  // Mean within 5 standard errors; sigma within 5 standard errors of a sample deviation
  // (sigma / sqrt(2 n)) plus float rounding of the stored values.
  const double n = static_cast<double>(s.count);
  EXPECT_NEAR(s.mean, mean, 5 * sigma / std::sqrt(n) + 1e-7 * mean);
  EXPECT_NEAR(s.sigma, sigma, 5 * sigma / std::sqrt(2 * n) + 1e-7 * mean);
}

TEST(SensorNoise, DepthCameraFollowsTheKinectModel) {
  for (const double distance : {1.0, 3.0}) {
    Scene scene;
    scene.mesh = MakeQuad(Eigen::Vector3d(-20, -20, distance), Eigen::Vector3d(40, 0, 0),
                          Eigen::Vector3d(0, 40, 0), 32);
    auto caster = RayCaster::Create(scene);
    ASSERT_TRUE(caster.ok());
    RecordingOptions options;
    options.seed = 3;
    const Simulator simulator(PointRobot(), Kinect(), **caster, StillPlan(), options);
    const SimSegment segment = simulator.Segment(0);
    ASSERT_EQ(segment.frames.size(), 1u);  // one frame per camera scan
    std::vector<double> z;
    std::size_t nans = 0;
    const auto& points = segment.frames[0].points;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const auto& p = points[i];
      if (std::isnan(p.z())) {
        ++nans;
        continue;
      }
      z.push_back(p.z());
      // Every point lies on its pixel's ray, whatever the noise along it.
      const double u = static_cast<double>(i % 320), v = static_cast<double>(i / 320);
      ASSERT_NEAR(p.x() / p.z(), (u - 159.5) / 208.5, 1e-6);
      ASSERT_NEAR(p.y() / p.z(), (v - 143.5) / 226.0, 1e-6);
    }
    EXPECT_EQ(nans, 0u);
    ExpectGaussian(Measure(z, nans), distance, 0.00253 + 0.0021 * distance);
    // Pixel (u, v) looks along ((u - cx) / fx, (v - cy) / fy, 1).
    const auto& corner = segment.frames[0].points[0];
    EXPECT_NEAR(corner.x() / corner.z(), -159.5 / 208.5, 1e-6);
    EXPECT_NEAR(corner.y() / corner.z(), -143.5 / 226.0, 1e-6);
  }
}

TEST(SensorNoise, OutOfRangeAndMissesAreNaN) {
  Scene scene;  // a wall beyond the Kinect's 5.46 m on the left half, nothing on the right
  scene.mesh = MakeQuad(Eigen::Vector3d(-20, -20, 6.0), Eigen::Vector3d(20, 0, 0),
                        Eigen::Vector3d(0, 40, 0));
  auto caster = RayCaster::Create(scene);
  ASSERT_TRUE(caster.ok());
  const Simulator simulator(PointRobot(), Kinect(), **caster, StillPlan(), RecordingOptions{});
  const SimSegment segment = simulator.Segment(0);
  ASSERT_EQ(segment.frames.size(), 1u);
  for (const auto& p : segment.frames[0].points) {
    ASSERT_TRUE(std::isnan(p.x()) && std::isnan(p.y()) && std::isnan(p.z()));
  }
}

TEST(SensorNoise, RotatingLidarFollowsTheHokuyoModel) {
  SensorModel lidar;
  lidar.kind = SensorLayout::kRotatingLidar;
  lidar.width = 1081;
  lidar.range_min = 0.1;
  lidar.range_max = 30;
  lidar.sigma_abs = 0.018;
  lidar.angle_first = -0.75 * std::numbers::pi;
  lidar.angle_increment = 2 * std::numbers::pi / 1440;
  lidar.rotation_period = 1.0 / 40;
  lidar.time_per_ray = lidar.rotation_period / 1440;
  Scene scene;  // inside a sphere of radius 3: every ray measures 3 m
  scene.spheres.push_back({Eigen::Vector3d::Zero(), 3.0});
  auto caster = RayCaster::Create(scene);
  ASSERT_TRUE(caster.ok());
  RecordingOptions options;
  options.stationary_hold = 0.5;
  const Simulator simulator(PointRobot(), lidar, **caster, StillPlan(), options);
  const SimSegment segment = simulator.Segment(0);
  // Rotations every 25 ms within the 0.5 s scan, each one 1081 rays.
  ASSERT_GE(segment.frames.size(), 19u);
  std::vector<double> ranges;
  for (std::size_t f = 0; f < segment.frames.size(); ++f) {
    ASSERT_EQ(segment.frames[f].ranges.size(), 1081u);
    if (f > 0) {
      EXPECT_EQ(segment.frames[f].stamp_us - segment.frames[f - 1].stamp_us, 25000);
    }
    for (float r : segment.frames[f].ranges) {
      ASSERT_FALSE(std::isnan(r));
      ranges.push_back(r);
    }
  }
  ExpectGaussian(Measure(ranges, 0), 3.0, 0.018);
}

TEST(SensorNoise, LineScannerFollowsTheWenglorModel) {
  SensorModel line;
  line.kind = SensorLayout::kLineScanner;
  line.width = 1280;
  line.range_min = 0.3;
  line.range_max = 1.5;
  line.sigma_abs = 0.0002;
  line.fan_angle = 0.5;
  line.line_period = 1.0 / 500;
  Scene scene;
  scene.mesh = MakeQuad(Eigen::Vector3d(-5, -5, 0.8), Eigen::Vector3d(10, 0, 0),
                        Eigen::Vector3d(0, 10, 0), 8);
  auto caster = RayCaster::Create(scene);
  ASSERT_TRUE(caster.ok());
  RecordingOptions options;
  options.stationary_hold = 0.1;
  const Simulator simulator(PointRobot(), line, **caster, StillPlan(), options);
  const SimSegment segment = simulator.Segment(0);
  ASSERT_GE(segment.frames.size(), 40u);  // 500 profiles/s for 0.1 s
  std::vector<double> z;
  for (const auto& frame : segment.frames) {
    ASSERT_EQ(frame.points.size(), 1280u);
    // Points lie in the xz plane, spread over the fan; the first point is at -x.
    EXPECT_LT(frame.points.front().x(), 0);
    EXPECT_NEAR(frame.points.front().x() / frame.points.front().z(), std::tan(-0.25 + 0.25 / 1280),
                1e-5);
    for (const auto& p : frame.points) {
      ASSERT_EQ(p.y(), 0.0f);
      z.push_back(p.z());
    }
  }
  ExpectGaussian(Measure(z, 0), 0.8, 0.0002);
}

TEST(SensorNoise, JointStatesHaveTheConfiguredEncoderNoiseAndRate) {
  Scene scene;
  scene.spheres.push_back({Eigen::Vector3d(0, 0, 2), 0.5});
  auto caster = RayCaster::Create(scene);
  ASSERT_TRUE(caster.ok());
  RecordingOptions options;
  options.joint_rate_hz = 1000;
  options.encoder_noise = 1e-4;
  options.timestamp_jitter = 5e-5;
  options.stationary_hold = 20.0;
  const Simulator simulator(PointRobot(), Kinect(), **caster, StillPlan(), options);
  const SimSegment segment = simulator.Segment(0);
  std::vector<double> q, jitter;
  for (std::size_t i = 0; i < segment.joint_states.size(); ++i) {
    const auto& state = segment.joint_states[i];
    q.push_back(state.positions[0]);
    jitter.push_back(static_cast<double>(state.stamp_us - state.device_stamp_us) * 1e-6);
    if (i > 0) {
      EXPECT_EQ(state.device_stamp_us - segment.joint_states[i - 1].device_stamp_us, 1000);
      EXPECT_GT(state.stamp_us, segment.joint_states[i - 1].stamp_us);  // host stamps in order
    }
  }
  ExpectGaussian(Measure(q, 0), 0.0, 1e-4);
  // Host-stamp jitter: Gaussian 50 us, clipped at 400 us; rounded to whole microseconds.
  const Stats j = Measure(jitter, 0);
  EXPECT_NEAR(j.mean, 0.0, 5e-6);
  EXPECT_NEAR(j.sigma, 5e-5, 3e-6);
}

}  // namespace
}  // namespace selfcal::sim
