// The device simulators' frames (core/sim/device_frame.h) on known geometry: the same systematic
// effects and multipath as `selfcal simulate` (compared with the Simulator's own frame), speckle
// along a line scanner's profile, flying pixels at a step edge, the sensor's noise on a plane,
// and the ideal ray casts with every effect off.
#include "core/sim/device_frame.h"

#include <gtest/gtest.h>

#include <cmath>
#include <utility>

#include "core/sim/simulator.h"
#include "tests/sim/small_world.h"

namespace selfcal::sim {
namespace {

using small_world::Camera;
using small_world::CornerScene;
using small_world::LineScanner;
using small_world::PointRobot;

// A near plane z = 1 left of x = 0, a far plane z = 1.5 behind it, tilted a little about y.
Scene StepScene() {
  Scene scene;
  scene.mesh = MakeQuad(Eigen::Vector3d(-5, -5, 1.0), Eigen::Vector3d(5, 0, 0.4),
                        Eigen::Vector3d(0, 10, 0), 16);
  scene.mesh.Append(MakeQuad(Eigen::Vector3d(-10, -10, 1.5), Eigen::Vector3d(20, 0, 0),
                             Eigen::Vector3d(0, 20, 0), 16));
  return scene;
}

// A plane z = 0.8 under a line scanner.
Scene PlaneScene() {
  Scene scene;
  scene.mesh = MakeQuad(Eigen::Vector3d(-5, -5, 0.8), Eigen::Vector3d(10, 0, 0),
                        Eigen::Vector3d(0, 10, 0), 16);
  return scene;
}

struct Fixture {
  explicit Fixture(Scene s = StepScene())
      : scene(std::move(s)), caster(std::move(RayCaster::Create(scene).value())) {}
  Scene scene;
  std::unique_ptr<RayCaster> caster;
};

std::vector<double> DeviceFrame(const Fixture& f, const SensorModel& sensor,
                                const FieldEffects& effects, std::uint64_t key) {
  const DeviceFrameCaster frames(*f.caster, PointRobot(), sensor, effects, 5);
  const std::vector<double> q = {0.0};
  const CellReturns cells =
      frames.Cast(frames.true_rays(), sensor.width, frames.SensorPose(q), frames.ArmLinks(q));
  return frames.Measure(cells, sensor.width, sensor.height, 100.0, key);
}

// What `selfcal simulate` records for the camera standing still at q = 0 in one scan: its first
// frame's points and that frame's device time [s].
struct SimulatedFrame {
  std::vector<Eigen::Vector3f> points;
  double device_time = 0;
};
SimulatedFrame SimulatorFrame(const Fixture& f, const FieldEffects& effects) {
  RecordingOptions options;
  options.effects = effects;
  options.stationary_hold = 0.1;
  ScanPlan plan;
  plan.scans.push_back({ScanPurpose::kFit, {0.0}, {0.0}, 0, -1});
  const Simulator simulator(PointRobot(), Camera(), *f.caster, plan, options);
  const SimSegment segment = simulator.Segment(0);
  const SimFrame& frame = segment.frames.at(0);
  return {frame.points, static_cast<double>(frame.device_stamp_us) * 1e-6};
}

TEST(DeviceFrame, SystematicEffectsAreTheSimulators) {
  // Range bias, intrinsics (focal length included), grazing dropout and projector shadows: what
  // selfcal simulate records, cell for cell, for a camera standing still 100 s into the run.
  FieldEffects effects;
  effects.range_bias = {true, 0.002, 0.001, 0.004, 0.003, 50};
  effects.intrinsics = {true, 0.004, 0.003, 0.01};
  effects.grazing_dropout = {true, 0.7};    // the image corners are lost
  effects.baseline_shadows = {true, -0.2};  // the projector left of the camera
  const Fixture f;
  const std::vector<double> device = DeviceFrame(f, Camera(), effects, 1);
  const SimulatedFrame simulated = SimulatorFrame(f, effects);
  const auto& points = simulated.points;
  const double t = simulated.device_time;
  // The warm-up term at the simulator's time instead of the device's 100 s.
  const double warmup = 0.003 * (std::exp(-t / 50) - std::exp(-100.0 / 50)) * 1.004;
  ASSERT_EQ(points.size(), device.size());
  int returns = 0, shadowed = 0;
  for (std::size_t i = 0; i < device.size(); ++i) {
    ASSERT_EQ(std::isnan(points[i].z()), std::isnan(device[i])) << "cell " << i;
    if (std::isnan(device[i])) {
      ++shadowed;
      continue;
    }
    ++returns;
    ASSERT_NEAR(points[i].z(), device[i] + warmup, 2e-6) << "cell " << i;
  }
  EXPECT_GT(returns, 50000);
  EXPECT_GT(shadowed, 100);  // lost at the grazing corners and where the projector cannot see
}

TEST(DeviceFrame, MultipathIsTheSimulators) {
  // The far plane reads longer near the corner's crease, as `selfcal simulate` records it (the
  // same grid of exact nodes and interpolated cells), and exactly away from it.
  FieldEffects effects;
  effects.multipath.enabled = true;  // documented default: 5 mm on the crease, radius 0.1 m
  const Fixture f(CornerScene());
  const std::vector<double> device = DeviceFrame(f, Camera(), effects, 1);
  const std::vector<double> ideal = DeviceFrame(f, Camera(), FieldEffects{}, 1);
  const auto points = SimulatorFrame(f, effects).points;
  ASSERT_EQ(points.size(), device.size());
  int longer = 0;
  for (std::size_t i = 0; i < device.size(); ++i) {
    ASSERT_EQ(std::isnan(points[i].z()), std::isnan(device[i])) << "cell " << i;
    if (std::isnan(device[i])) continue;
    ASSERT_NEAR(points[i].z(), device[i], 2e-6) << "cell " << i;
    ASSERT_GE(device[i], ideal[i]) << "cell " << i;
    if (device[i] > ideal[i] + 0.001) ++longer;
  }
  // Within a few centimetres of the crease on the plane's side: some 16 columns of 288 rows.
  EXPECT_GT(longer, 2500);
  EXPECT_LT(longer, 7000);
}

TEST(DeviceFrame, SpeckleCorrelatesALineScannersNoiseAlongTheLine) {
  const Fixture f(PlaneScene());
  // The noise of 40 profiles: its RMS and the correlation of neighbours along the line.
  auto noise = [&](const FieldEffects& effects) {
    double squares = 0, neighbours = 0;
    std::size_t count = 0;
    for (std::uint64_t key = 0; key < 40; ++key) {
      const std::vector<double> profile = DeviceFrame(f, LineScanner(0.0002), effects, key);
      for (std::size_t i = 0; i < profile.size(); ++i) {
        const double r = profile[i] - 0.8;
        squares += r * r;
        ++count;
        if (i + 1 < profile.size()) neighbours += r * (profile[i + 1] - 0.8);
      }
    }
    return std::pair{std::sqrt(squares / static_cast<double>(count)), neighbours / squares};
  };
  FieldEffects effects;
  effects.speckle.enabled = true;  // documented default: correlation length 3 points
  const auto [sigma, correlation] = noise(effects);
  EXPECT_NEAR(sigma, 0.0002, 0.0002 * 0.05);  // the file's sigma
  EXPECT_NEAR(correlation, std::exp(-1.0 / 9), 0.05);
  const auto [white_sigma, white_correlation] = noise(FieldEffects{});
  EXPECT_NEAR(white_sigma, 0.0002, 0.0002 * 0.05);
  EXPECT_NEAR(white_correlation, 0, 0.03);
}

TEST(DeviceFrame, StepEdgeGetsFlyingPixelsAndPlanesGetTheNoise) {
  FieldEffects effects;
  effects.mixed_pixels.enabled = true;  // probability 0.5, min_jump 2 cm
  const Fixture f;
  const double sigma = 0.001;
  const std::vector<double> frame = DeviceFrame(f, Camera(sigma), effects, 7);
  EXPECT_EQ(frame, DeviceFrame(f, Camera(sigma), effects, 7));  // same key, same frame
  EXPECT_NE(frame, DeviceFrame(f, Camera(sigma), effects, 8));
  const std::vector<double> ideal = DeviceFrame(f, Camera(), FieldEffects{}, 7);
  int mixed = 0, plane = 0;
  double squares = 0;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    ASSERT_FALSE(std::isnan(frame[i]));
    const double error = frame[i] - ideal[i];
    if (std::abs(error) < 6 * sigma) {
      squares += error * error;
      ++plane;
      continue;
    }
    // A flying pixel: between the near and the far surface, beside the edge.
    ++mixed;
    EXPECT_GT(frame[i], 1.0 - 6 * sigma);
    EXPECT_LT(frame[i], 1.5 + 6 * sigma);
  }
  // About 2 columns x 288 rows beside the edge, half of them mixed (a few within 6 sigma).
  EXPECT_GT(mixed, 200);
  EXPECT_LT(mixed, 360);
  EXPECT_NEAR(std::sqrt(squares / plane), sigma, 0.03 * sigma);
}

TEST(DeviceFrame, TheWalkerAndTheMovedBoxAreTheSimulatorsInTheirScan) {
  // A person standing 0.5 m in front of the camera during scan 0 (from = to: the fraction of the
  // walk does not matter), and a box that is moved 0.1 m towards it before scan 1.
  FieldEffects effects;
  effects.walker = {true, {0}, Eigen::Vector3d(0.15, 0.1, 0.5), Eigen::Vector3d(0.15, 0.1, 0.5),
                    0.1,  0.4};
  effects.moved_object = {true, 1, Eigen::Vector3d::Constant(0.1), Eigen::Vector3d(-0.2, -0.1, 0.7),
                          Eigen::Vector3d(0, 0, -0.1)};
  const Fixture f;
  const SensorModel camera = Camera();
  const DeviceFrameCaster frames(*f.caster, PointRobot(), camera, effects, 5);
  const std::vector<double> q = {0.0};
  auto frame_of_scan = [&](int scan) {
    const CellReturns cells = frames.Cast(frames.true_rays(), camera.width, frames.SensorPose(q),
                                          frames.Moving(q, scan, 0.5));
    return frames.Measure(cells, camera.width, camera.height, 100.0, 1);
  };
  const std::vector<double> scan0 = frame_of_scan(0), scan1 = frame_of_scan(1);
  const auto points = SimulatorFrame(f, effects).points;  // its one scan is scan 0
  ASSERT_EQ(points.size(), scan0.size());
  int walker = 0, box_before = 0, box_after = 0;
  for (std::size_t i = 0; i < scan0.size(); ++i) {
    ASSERT_EQ(std::isnan(points[i].z()), std::isnan(scan0[i])) << "cell " << i;
    if (!std::isnan(scan0[i])) {
      ASSERT_NEAR(points[i].z(), scan0[i], 2e-6) << "cell " << i;
    }
    walker += scan0[i] < 0.65 ? 1 : 0;  // the walker's front at z 0.5 - 0.6
    box_before += std::abs(scan0[i] - 0.7) < 1e-9 ? 1 : 0;
    box_after += std::abs(scan1[i] - 0.6) < 1e-9 ? 1 : 0;
    ASSERT_FALSE(scan1[i] < 0.59) << "cell " << i << ": no walker in scan 1";
  }
  EXPECT_GT(walker, 2000);
  EXPECT_GT(box_before, 500);
  EXPECT_GT(box_after, 500);
}

TEST(DeviceFrame, ThermalGrowthIsTheSimulatorsAtTheSameTimeIntoTheRecording) {
  FieldEffects effects;
  effects.thermal_growth.enabled = true;  // 23 ppm/K, 3 K after warming up, 600 s
  RobotModel robot = PointRobot();
  robot.base.z = 0.4;
  robot.tool.x = 0.3;
  robot.tool.z = 0.5;
  const Fixture f;
  const DeviceFrameCaster frames(*f.caster, robot, Camera(), effects, 5);
  RecordingOptions options;
  options.effects = effects;
  const Simulator simulator(robot, Camera(), *f.caster, small_world::StillPlan(), options);
  const std::vector<double> q = {0.0};
  for (const double t : {0.0, 300.0, 3600.0}) {
    EXPECT_LT((frames.SensorPose(q, t).matrix() - simulator.TrueSensorPose(t).matrix()).norm(),
              1e-12)
        << t << " s";
  }
  // Every length of the arm grows alike, so the sensor's position scales: 69 um a metre by 3 K.
  const Eigen::Vector3d cold = frames.SensorPose(q, 0).translation();
  const Eigen::Vector3d warm = frames.SensorPose(q, 3600).translation();
  EXPECT_NEAR((warm - cold).norm() / cold.norm(), 23e-6 * 3 * (1 - std::exp(-6.0)), 1e-9);
}

TEST(DeviceFrame, EveryEffectOffIsTheIdealRayCast) {
  const Fixture f;
  const SensorModel camera = Camera();
  const std::vector<double> frame = DeviceFrame(f, camera, FieldEffects{}, 3);
  const std::vector<Eigen::Vector3d> rays = camera.Rays();
  for (std::size_t i = 0; i < frame.size(); ++i) {
    const double length = rays[i].norm();
    const double depth = f.caster->Cast(Eigen::Vector3d::Zero(), rays[i] / length) / length;
    ASSERT_EQ(frame[i], depth) << "cell " << i;
  }
}

}  // namespace
}  // namespace selfcal::sim
