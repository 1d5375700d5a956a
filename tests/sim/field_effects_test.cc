// Field effects, each on a known geometry (a plane, a step edge, a corner) with its documented
// magnitude: flying pixels at a step, range bias and incidence noise on a tilted plane, lost
// returns at grazing angles, baseline shadows behind an edge, intrinsics off, gravity
// deflection of a horizontal arm, lagging joint states, the arm and moving things as capsules
// and boxes, multipath in a corner, dark surfaces, speckle along a line, thermal growth,
// backlash on reversal and clock drift.
#include "core/sim/field_effects.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/model/kinematics.h"
#include "core/sim/ray_caster.h"
#include "core/sim/simulator.h"
#include "protocols/model_file/model_file.h"
#include "protocols/scenario/effects_file.h"
#include "tests/sim/small_world.h"

namespace selfcal::sim {
namespace {

using small_world::Camera;
using small_world::CornerScene;
using small_world::LineScanner;
using small_world::PointRobot;
using small_world::StillPlan;

std::string Source(const std::string& relative) {
  const char* root = std::getenv("SELFCAL_SOURCE_DIR");
  return std::string(root ? root : ".") + "/" + relative;
}

SensorModel Lidar() {
  SensorModel lidar;
  lidar.kind = SensorLayout::kRotatingLidar;
  lidar.width = 1081;
  lidar.range_min = 0.1;
  lidar.range_max = 30;
  lidar.angle_first = -0.75 * std::numbers::pi;
  lidar.angle_increment = 2 * std::numbers::pi / 1440;
  lidar.rotation_period = 1.0 / 40;
  lidar.time_per_ray = lidar.rotation_period / 1440;
  return lidar;
}

SimSegment SimulateScan(const Scene& scene, const SensorModel& sensor, const FieldEffects& effects,
                        double hold = 0.1) {
  auto caster = RayCaster::Create(scene);
  EXPECT_TRUE(caster.ok());
  RecordingOptions options;
  options.seed = 5;
  options.stationary_hold = hold;
  options.effects = effects;
  const Simulator simulator(PointRobot(), sensor, **caster, StillPlan(), options);
  return simulator.Segment(0);
}

// A plane through (0, 0, distance) with normal (sin tilt, 0, cos tilt), seen by the camera.
Scene TiltedPlane(double distance, double tilt) {
  Scene scene;
  const Eigen::Vector3d centre(0, 0, distance);
  const Eigen::Vector3d u(std::cos(tilt), 0, -std::sin(tilt));
  const Eigen::Vector3d v(0, 1, 0);
  scene.mesh = MakeQuad(centre - 20 * u - 20 * v, 40 * v, 40 * u, 64);
  return scene;
}

// Camera pixel ray (unit) and the depth z where it meets TiltedPlane.
Eigen::Vector3d PixelRay(const SensorModel& m, std::size_t i) {
  const double u = static_cast<double>(i % static_cast<std::size_t>(m.width));
  const double v = static_cast<double>(i / static_cast<std::size_t>(m.width));
  return m.intrinsics.Unproject(u, v, 1.0);
}
double PlaneDepth(const Eigen::Vector3d& ray, double distance, double tilt) {
  const Eigen::Vector3d n(std::sin(tilt), 0, std::cos(tilt));
  return n.dot(Eigen::Vector3d(0, 0, distance)) / n.dot(ray);
}

TEST(FieldEffects, FlyingPixelsAppearOnlyAtAStepEdge) {
  Scene scene;  // near plane z = 1 left of x = 0, far plane z = 1.5 behind it
  scene.mesh = MakeQuad(Eigen::Vector3d(-5, -5, 1.0), Eigen::Vector3d(5, 0, 0),
                        Eigen::Vector3d(0, 10, 0), 16);
  scene.mesh.Append(MakeQuad(Eigen::Vector3d(-10, -10, 1.5), Eigen::Vector3d(20, 0, 0),
                             Eigen::Vector3d(0, 20, 0), 16));
  FieldEffects effects;
  effects.mixed_pixels.enabled = true;  // documented default: probability 0.5, min_jump 2 cm
  const SimSegment segment = SimulateScan(scene, Camera(), effects);
  const auto& points = segment.frames.at(0).points;
  int mixed = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double z = points[i].z();
    ASSERT_FALSE(std::isnan(z));
    if (std::abs(z - 1.0) < 1e-6 || std::abs(z - 1.5) < 1e-6) continue;
    // A flying pixel lies between the two surfaces, on its own ray, next to the edge.
    EXPECT_GT(z, 1.0);
    EXPECT_LT(z, 1.5);
    const std::size_t u = i % 320;
    EXPECT_TRUE(u == 159 || u == 160) << "column " << u;
    ++mixed;
  }
  // 2 columns x 288 rows at the edge, half of them mixed: binomial, 5 sigma = 60.
  EXPECT_NEAR(mixed, 288, 60);
}

TEST(FieldEffects, AContinuousSurfaceAtAGrazingAngleHasNoFlyingPixels) {
  // At 80 degrees and 1.5 m the depth grows by 2-10 cm from one column to the next (more than
  // min_jump), yet every sample lies on the one plane: no footprint straddles two surfaces.
  FieldEffects effects;
  effects.mixed_pixels.enabled = true;
  effects.mixed_pixels.probability = 1.0;
  const double tilt = 80.0 * M_PI / 180.0;
  const SimSegment segment = SimulateScan(TiltedPlane(1.5, tilt), Camera(), effects);
  const auto& points = segment.frames.at(0).points;
  int steep = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (std::isnan(points[i].z())) continue;
    const double expected = PlaneDepth(PixelRay(Camera(), i), 1.5, tilt);
    // Beyond 5 m a neighbour lies past the sensor's range: there the cell has no continuation
    // to compare with, and the rule falls back to the plain jump.
    if (expected > 5.0) continue;
    ASSERT_NEAR(points[i].z(), expected, 1e-5 * expected) << "pixel " << i;
    if (i % 320 + 1 < 320 && !std::isnan(points[i + 1].z()))
      steep += std::abs(points[i + 1].z() - points[i].z()) > effects.mixed_pixels.min_jump;
  }
  EXPECT_GT(steep, 1000);  // the test means something: many neighbours differ by more
}

TEST(FieldEffects, LidarMixesTheEdgeRaysOfAStep) {
  Scene scene;  // a wall at x = 2 for y < 0, a wall at x = 3 for y > 0
  scene.mesh =
      MakeQuad(Eigen::Vector3d(2, -5, -5), Eigen::Vector3d(0, 5, 0), Eigen::Vector3d(0, 0, 10), 8);
  scene.mesh.Append(MakeQuad(Eigen::Vector3d(3, -5, -5), Eigen::Vector3d(0, 10, 0),
                             Eigen::Vector3d(0, 0, 10), 8));
  FieldEffects effects;
  effects.mixed_pixels.enabled = true;
  effects.mixed_pixels.probability = 1.0;
  SensorModel lidar = Lidar();
  lidar.angle_first = -0.5;  // 0.25 deg steps; ray 114 is the last one left of the edge
  lidar.width = 229;
  const SimSegment segment = SimulateScan(scene, lidar, effects, 0.1);
  ASSERT_GE(segment.frames.size(), 3u);
  for (const auto& frame : segment.frames) {
    int mixed = 0;
    for (std::size_t i = 0; i < frame.ranges.size(); ++i) {
      const double angle = lidar.angle_first + static_cast<double>(i) * lidar.angle_increment;
      const double clean = (angle < 0 ? 2.0 : 3.0) / std::cos(angle);
      if (std::abs(frame.ranges[i] - clean) < 1e-4) continue;
      ++mixed;
      EXPECT_GT(frame.ranges[i], 2.0 / std::cos(angle) - 1e-4);
      EXPECT_LT(frame.ranges[i], 3.0 / std::cos(angle) + 1e-4);
    }
    EXPECT_EQ(mixed, 2);  // the two rays beside the edge, one on each side
  }
}

TEST(FieldEffects, RangeBiasAndIntrinsicsOnAPlane) {
  FieldEffects effects;
  effects.range_bias.enabled = true;
  effects.range_bias.offset = 0.002;
  effects.range_bias.per_metre = 0.001;
  effects.intrinsics.enabled = true;
  effects.intrinsics.depth_scale = 0.004;
  effects.intrinsics.range_offset = 0.003;
  const SimSegment segment = SimulateScan(TiltedPlane(1.5, 0.0), Camera(), effects);
  const double biased = 1.5 + 0.002 + 0.001 * 1.5;
  const double expected = biased * 1.004 + 0.003;
  for (const auto& p : segment.frames.at(0).points) ASSERT_NEAR(p.z(), expected, 2e-6);
}

TEST(FieldEffects, WarmupDriftDecaysWithItsTimeConstant) {
  RangeBiasEffect effect;
  effect.enabled = true;
  effect.warmup_offset = 0.004;
  effect.warmup_time_constant = 900;
  EXPECT_DOUBLE_EQ(RangeBias(effect, 1.0, 1.0, 0), 0.004);
  EXPECT_NEAR(RangeBias(effect, 1.0, 1.0, 900), 0.004 / std::numbers::e, 1e-12);
  EXPECT_EQ(RangeBias(RangeBiasEffect{}, 1.0, 0.5, 0), 0);  // off: nothing
}

TEST(FieldEffects, FocalLengthErrorShiftsAnEdgeInTheImage) {
  Scene scene;  // a far plane, and a near one right of x / z = 0.2
  scene.mesh = MakeQuad(Eigen::Vector3d(0.2, -5, 1.0), Eigen::Vector3d(5, 0, 0),
                        Eigen::Vector3d(0, 10, 0), 16);
  scene.mesh.Append(MakeQuad(Eigen::Vector3d(-10, -10, 2.0), Eigen::Vector3d(20, 0, 0),
                             Eigen::Vector3d(0, 20, 0), 16));
  auto first_near_column = [&](const FieldEffects& effects) {
    const SimSegment segment = SimulateScan(scene, Camera(), effects);
    const auto& points = segment.frames.at(0).points;
    const std::size_t row = 143 * 320;
    for (std::size_t u = 0; u < 320; ++u) {
      if (points[row + u].z() < 1.5) {
        // The recorded point stays on the file's ray of its pixel.
        EXPECT_NEAR(points[row + u].x() / points[row + u].z(),
                    (static_cast<double>(u) - 159.5) / 208.5, 1e-6);
        return static_cast<int>(u);
      }
    }
    return -1;
  };
  FieldEffects off;
  FieldEffects focal;
  focal.intrinsics.enabled = true;
  focal.intrinsics.focal_scale = 0.05;
  // Pixel u sees x / z = (u - cx) / (fx (1 + e)): the edge moves from cx + 0.2 fx to
  // cx + 0.2 fx (1 + e), columns 201.2 -> 203.3.
  EXPECT_EQ(first_near_column(off), static_cast<int>(std::ceil(159.5 + 0.2 * 208.5)));
  EXPECT_EQ(first_near_column(focal), static_cast<int>(std::ceil(159.5 + 0.2 * 208.5 * 1.05)));
}

TEST(FieldEffects, NoiseGrowsWithIncidenceOnATiltedPlane) {
  const double tilt = std::numbers::pi / 3;  // 60 deg: the noise doubles at exponent 1
  SensorModel camera = Camera();
  camera.sigma_abs = 0.002;
  FieldEffects effects;
  effects.incidence_noise.enabled = true;
  const SimSegment segment = SimulateScan(TiltedPlane(1.5, tilt), camera, effects);
  const Eigen::Vector3d n(std::sin(tilt), 0, std::cos(tilt));
  double sum = 0;
  int count = 0;
  const auto& points = segment.frames.at(0).points;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (std::isnan(points[i].z())) continue;
    const Eigen::Vector3d ray = PixelRay(camera, i);
    const double cosine = std::abs(n.dot(ray.normalized()));
    const double factor = std::min(4.0, 1 / cosine);
    const double residual = (points[i].z() - PlaneDepth(ray, 1.5, tilt)) / (0.002 * factor);
    sum += residual * residual;
    ++count;
  }
  ASSERT_GT(count, 50000);
  EXPECT_NEAR(std::sqrt(sum / count), 1.0, 0.02);
  EXPECT_NEAR(IncidenceNoiseFactor(effects.incidence_noise, 0.5), 2.0, 1e-12);
}

TEST(FieldEffects, GrazingReturnsAreLost) {
  const double tilt = 1.35;  // 77 deg at the image centre, 60-90 deg across the image
  FieldEffects effects;
  effects.grazing_dropout.enabled = true;  // documented default: lost beyond 75 deg
  const SimSegment segment = SimulateScan(TiltedPlane(1.5, tilt), Camera(), effects);
  const Eigen::Vector3d n(std::sin(tilt), 0, std::cos(tilt));
  int lost = 0, kept = 0;
  const auto& points = segment.frames.at(0).points;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d ray = PixelRay(Camera(), i);
    const double depth = PlaneDepth(ray, 1.5, tilt);
    if (!(depth > 0.3 && depth < 5.4)) continue;  // outside the view range either way
    const double angle = std::acos(std::abs(n.dot(ray.normalized())));
    if (std::abs(angle - 1.31) < 2e-3) continue;
    if (angle > 1.31) {
      EXPECT_TRUE(std::isnan(points[i].z())) << "pixel " << i << " at " << angle;
      ++lost;
    } else {
      EXPECT_FALSE(std::isnan(points[i].z()));
      ++kept;
    }
  }
  EXPECT_GT(lost, 1000);
  EXPECT_GT(kept, 1000);
}

TEST(FieldEffects, HokuyoRangeBiasGrowsWithIncidence) {
  Scene scene;  // a wall at x = 2: the incidence angle of ray a is a
  scene.mesh = MakeQuad(Eigen::Vector3d(2, -5, -5), Eigen::Vector3d(0, 10, 0),
                        Eigen::Vector3d(0, 0, 10), 16);
  FieldEffects effects;
  effects.range_bias.enabled = true;
  effects.range_bias.incidence = 0.01;
  SensorModel lidar = Lidar();
  lidar.angle_first = -1.0;
  lidar.width = 459;  // -1 .. +1 rad
  const SimSegment segment = SimulateScan(scene, lidar, effects, 0.03);
  const auto& ranges = segment.frames.at(0).ranges;
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    const double angle = lidar.angle_first + static_cast<double>(i) * lidar.angle_increment;
    ASSERT_NEAR(ranges[i], 2 / std::cos(angle) + 0.01 * (1 - std::cos(angle)), 2e-5) << i;
  }
}

TEST(FieldEffects, LineScannerLosesWhatItsCameraCannotSee) {
  // The laser line (y = 0) lies on a floor at z = 0.8; a box between it and the camera at
  // (0, 0.1, 0) covers x > 0 only, so the camera sees the line's left half only.
  Scene scene;
  scene.mesh = MakeQuad(Eigen::Vector3d(-5, -5, 0.8), Eigen::Vector3d(10, 0, 0),
                        Eigen::Vector3d(0, 10, 0), 16);
  scene.mesh.Append(MakeBox(Eigen::Vector3d(0.0, 0.01, 0.6), Eigen::Vector3d(1.0, 0.3, 0.7)));
  FieldEffects effects;
  effects.baseline_shadows.enabled = true;
  effects.baseline_shadows.baseline = 0.1;
  const SimSegment shadowed = SimulateScan(scene, LineScanner(), effects);
  const SimSegment clear = SimulateScan(scene, LineScanner(), FieldEffects{});
  const auto& with = shadowed.frames.at(0).points;
  const auto& without = clear.frames.at(0).points;
  for (std::size_t i = 0; i < with.size(); ++i) {
    ASSERT_NEAR(without[i].z(), 0.8, 1e-5);
    if (without[i].x() < -1e-3) {
      EXPECT_NEAR(with[i].z(), 0.8, 1e-5) << i;
    }
    if (without[i].x() > 1e-3) {
      EXPECT_TRUE(std::isnan(with[i].z())) << i;
    }
  }
}

TEST(FieldEffects, StructuredLightHasHolesWhereItsProjectorCannotSee) {
  // A far plane z = 1 and a box edge in front (x >= 0.02, z 0.5..0.6); the projector at
  // (0.1, 0, 0) lights the plane only for x < -0.06 (its line past the box's upper-left edge).
  Scene scene;
  scene.mesh = MakeQuad(Eigen::Vector3d(-10, -10, 1.0), Eigen::Vector3d(20, 0, 0),
                        Eigen::Vector3d(0, 20, 0), 16);
  scene.mesh.Append(MakeBox(Eigen::Vector3d(0.02, -5, 0.5), Eigen::Vector3d(2.0, 5, 0.6)));
  FieldEffects effects;
  effects.baseline_shadows.enabled = true;
  effects.baseline_shadows.baseline = 0.1;
  const SimSegment segment = SimulateScan(scene, Camera(), effects);
  const auto& points = segment.frames.at(0).points;
  int holes = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double x = PixelRay(Camera(), i).x();  // on the plane z = 1
    if (x < -0.06 - 1e-3) {
      EXPECT_NEAR(points[i].z(), 1.0, 1e-5) << i;
    }
    if (x > -0.06 + 1e-3 && x < 0.02 / 0.6 - 1e-3) {
      EXPECT_TRUE(std::isnan(points[i].z())) << i;
      ++holes;
    }
  }
  EXPECT_GT(holes, 288 * 15);
}

TEST(FieldEffects, GravityDeflectsAHorizontalIiwa) {
  const auto file = ReadModelFile(Source("config/robots/kuka_lbr_iiwa_r840.yaml"));
  ASSERT_TRUE(file.ok()) << file.error().message;
  const RobotModel& model = file->model;
  const std::vector<double> k = ToParameterVector(model);
  const std::vector<JointType> types = JointTypes(model);
  const std::vector<double> q = {0, std::numbers::pi / 2, 0, 0, 0, 0, 0};  // arm straight out
  const ArmFrames frames = ComputeArmFrames(types, k.data(), q.data());
  const JointElasticityEffect effect = [] {
    JointElasticityEffect e = IiwaElasticity();
    e.enabled = true;
    return e;
  }();
  const std::vector<double> deflection =
      GravityDeflection(effect, frames.axes, frames.origins, frames.tool_point);
  // A2 carries links 2..7 and the sensor at their lever arms (0.21, 0.62, 0.883, 0.946 m).
  const double torque =
      9.81 * ((6.35 + 3.5) * 0.21 + (3.5 + 3.5) * 0.62 + (1.8 + 1.2) * 0.883 + 0.5 * 0.946);
  EXPECT_NEAR(std::abs(deflection[1]), torque / 2.0e4, 1e-9);
  EXPECT_NEAR(deflection[0], 0, 1e-12);  // a vertical axis carries no gravity torque
  // The deflection lowers the tool (about 4 mm with the stated stiffness).
  std::vector<double> sagged = q;
  for (std::size_t j = 0; j < q.size(); ++j) sagged[j] += deflection[j];
  const double drop = ForwardKinematics(model, q).translation().z() -
                      ForwardKinematics(model, sagged).translation().z();
  EXPECT_GT(drop, 0.003);
  EXPECT_LT(drop, 0.008);
  // Straight up, nothing bends.
  const std::vector<double> up(7, 0.0);
  const ArmFrames upright = ComputeArmFrames(types, k.data(), up.data());
  for (double d : GravityDeflection(effect, upright.axes, upright.origins, upright.tool_point)) {
    EXPECT_NEAR(d, 0, 1e-12);
  }
}

TEST(FieldEffects, JointStatesLagTheMotion) {
  ScanPlan plan;
  PlannedScan scan;
  scan.start = {0.0};
  scan.end = {1.0};
  scan.peak_rate = 0.5;
  plan.scans.push_back(scan);
  Scene scene;
  scene.spheres.push_back({Eigen::Vector3d(0, 0, 2), 0.5});
  auto caster = RayCaster::Create(scene);
  ASSERT_TRUE(caster.ok());
  RecordingOptions options;
  options.encoder_noise = 0;
  const Simulator ideal(PointRobot(), Lidar(), **caster, plan, options);
  options.effects.timing.enabled = true;
  options.effects.timing.joint_lag = 0.005;  // one sample at 200 Hz
  const Simulator lagging(PointRobot(), Lidar(), **caster, plan, options);
  const SimSegment a = ideal.Segment(0), b = lagging.Segment(0);
  ASSERT_EQ(a.joint_states.size(), b.joint_states.size());
  double largest = 0;
  for (std::size_t n = 1; n < a.joint_states.size(); ++n) {
    EXPECT_NEAR(b.joint_states[n].positions[0], a.joint_states[n - 1].positions[0], 1e-9);
    largest = std::max(largest, a.joint_states[n].positions[0] - b.joint_states[n].positions[0]);
  }
  EXPECT_GT(largest, 0.002);  // 0.5 rad/s for 5 ms
}

TEST(FieldEffects, CapsulesAndBoxesAreHitWhereExpected) {
  const Capsule capsule{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 0, 1), 0.1};
  Eigen::Vector3d normal;
  EXPECT_NEAR(CastCapsule(capsule, Eigen::Vector3d(1, 0, 0.5), -Eigen::Vector3d::UnitX(), &normal),
              0.9, 1e-12);
  EXPECT_NEAR(normal.x(), 1.0, 1e-12);
  EXPECT_NEAR(CastCapsule(capsule, Eigen::Vector3d(0, 0, -1), Eigen::Vector3d::UnitZ(), &normal),
              0.9, 1e-12);
  EXPECT_NEAR(normal.z(), -1.0, 1e-12);
  EXPECT_TRUE(std::isinf(
      CastCapsule(capsule, Eigen::Vector3d(0, 0, 0.5), Eigen::Vector3d::UnitX(), nullptr)));
  EXPECT_TRUE(std::isinf(
      CastCapsule(capsule, Eigen::Vector3d(1, 0, 0.5), Eigen::Vector3d::UnitX(), nullptr)));
  const Eigen::AlignedBox3d box(Eigen::Vector3d(1, -1, -1), Eigen::Vector3d(2, 1, 1));
  EXPECT_NEAR(CastBox(box, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), &normal), 1.0, 1e-12);
  EXPECT_NEAR(normal.x(), -1.0, 1e-12);
}

TEST(FieldEffects, TheArmSeesItsOwnLinks) {
  const auto file = ReadModelFile(Source("config/robots/kuka_lbr_iiwa_r840.yaml"));
  ASSERT_TRUE(file.ok());
  const std::vector<double> k = ToParameterVector(file->model);
  const std::vector<JointType> types = JointTypes(file->model);
  const std::vector<double> up(7, 0.0);  // upright: base, J2, J4, J6 and the flange on z
  const ArmFrames frames = ComputeArmFrames(types, k.data(), up.data());
  DynamicGeometry geometry;
  geometry.capsules = ArmCapsules(frames, 0.07);
  ASSERT_EQ(geometry.capsules.size(), 4u);
  EXPECT_NEAR(frames.tool_point.z(), 0.36 + 0.42 + 0.40 + 0.126, 1e-9);
  // Looking down from the flange (inside its own link) the sensor sees the forearm's top.
  EXPECT_NEAR(geometry.Cast(frames.tool_point, -Eigen::Vector3d::UnitZ(), 10, nullptr),
              0.126 - 0.07, 1e-9);
}

TEST(FieldEffects, AWalkerCrossesAndAnObjectMoves) {
  FieldEffects effects;
  effects.walker.enabled = true;
  effects.walker.scans = {2};
  effects.walker.from = Eigen::Vector3d(2, -1, 0);
  effects.walker.to = Eigen::Vector3d(2, 1, 0);
  effects.moved_object.enabled = true;
  effects.moved_object.after_scan = 3;
  effects.moved_object.position = Eigen::Vector3d(0, 3, 0);
  effects.moved_object.shift = Eigen::Vector3d(0, 0.5, 0);
  const Eigen::Vector3d eye(0, 0, 1);
  for (int scan : {1, 2, 3}) {
    DynamicGeometry geometry;
    AddSceneMotion(effects, scan, 0.5, geometry);
    const double walker = geometry.Cast(eye, Eigen::Vector3d::UnitX(), 10, nullptr);
    if (scan == 2) {
      EXPECT_NEAR(walker, 2 - 0.25, 1e-12);  // in the middle of its walk, in front of us
    } else {
      EXPECT_TRUE(std::isinf(walker));
    }
    const double box =
        geometry.Cast(Eigen::Vector3d(0, 0, 0.1), Eigen::Vector3d::UnitY(), 10, nullptr);
    EXPECT_NEAR(box, scan < 3 ? 2.9 : 3.4, 1e-12);
  }
}

TEST(FieldEffects, MultipathBiasesACornerNearItsCrease) {
  MultipathEffect effect;
  effect.enabled = true;  // documented default: 5 mm on the crease, radius 0.1 m, 16 samples
  const Scene corner = CornerScene();
  auto caster = RayCaster::Create(corner);
  ASSERT_TRUE(caster.ok());
  const DynamicGeometry none;
  const Eigen::Vector3d normal(0, 0, -1);  // the far plane, towards the camera
  double previous = 1;
  for (double gap : {0.001, 0.01, 0.03, 0.05, 0.07, 0.09, 0.11, 0.3}) {
    const Eigen::Vector3d point(0.2 - gap, 0.1, 1);
    const double excess = MultipathExcess(effect, **caster, none, point, normal);
    if (gap == 0.001) {
      // On the crease half the cosine-weighted hemisphere sees the wall (16 fixed directions).
      EXPECT_NEAR(excess, 0.005, 0.005 * 2.0 / 16 + 1e-9);
    }
    EXPECT_LE(excess, previous + 1e-12) << gap;  // decays away from the crease
    if (gap > 0.1) {
      EXPECT_EQ(excess, 0) << gap;  // beyond the radius: nothing
    }
    if (gap < 0.05) {
      EXPECT_GT(excess, 0) << gap;
    }
    previous = excess;
  }
  // Through the simulator (exact every 8th pixel, interpolated between): the far plane reads
  // longer near the crease only, within 0.5 mm of the exact excess; a plane alone reads exactly.
  FieldEffects effects;
  effects.multipath = effect;
  const SimSegment cornered = SimulateScan(corner, Camera(), effects);
  const auto& points = cornered.frames.at(0).points;
  Scene plane;
  plane.mesh =
      MakeQuad(Eigen::Vector3d(-3, -3, 1), Eigen::Vector3d(6, 0, 0), Eigen::Vector3d(0, 6, 0), 32);
  const SimSegment planar = SimulateScan(plane, Camera(), effects);
  const auto& flat = planar.frames.at(0).points;
  const std::size_t row = 143 * 320;
  int near_crease = 0;
  for (std::size_t u = 0; u < 320; ++u) {
    EXPECT_NEAR(flat[row + u].z(), 1.0, 1e-6) << u;
    const Eigen::Vector3d hit = PixelRay(Camera(), row + u);  // on the far plane z = 1
    if (hit.x() > 0.2) continue;                              // the wall
    const double excess = points[row + u].z() - 1.0;
    EXPECT_NEAR(excess, MultipathExcess(effect, **caster, none, hit, normal) / hit.norm(), 5e-4)
        << u;
    if (hit.x() < 0.2 - 0.1 - 8 / 208.5) {  // beyond the radius and one grid step
      EXPECT_NEAR(excess, 0, 1e-6) << u;
    } else if (hit.x() > 0.2 - 0.02) {
      EXPECT_GT(excess, 0.001) << u;
      ++near_crease;
    }
  }
  EXPECT_GT(near_crease, 2);
}

// A wall at x = 2 seen by a LiDAR: white (albedo 1) for y < 0, dark (`dark`) for y > 0.
Scene TwoToneWall(float dark) {
  Scene scene;
  scene.mesh =
      MakeQuad(Eigen::Vector3d(2, -5, -5), Eigen::Vector3d(0, 5, 0), Eigen::Vector3d(0, 0, 10), 8);
  const std::size_t white = scene.mesh.triangles.size();
  scene.mesh.Append(
      MakeQuad(Eigen::Vector3d(2, 0, -5), Eigen::Vector3d(0, 5, 0), Eigen::Vector3d(0, 0, 10), 8));
  scene.albedo.assign(scene.mesh.triangles.size(), dark);
  std::fill(scene.albedo.begin(), scene.albedo.begin() + static_cast<std::ptrdiff_t>(white), 1.0f);
  return scene;
}

TEST(FieldEffects, DarkSurfacesLoseReturnsAndReadLonger) {
  FieldEffects effects;
  effects.dark_dropout.enabled = true;
  effects.dark_dropout.threshold = 0.001;  // the Hokuyo's documented value
  effects.range_bias.enabled = true;
  effects.range_bias.reflectivity = 0.01;  // the Hokuyo's documented value
  SensorModel lidar = Lidar();
  lidar.angle_first = -1.0;
  lidar.width = 459;  // -1 .. +1 rad
  const float dark = 0.003f;
  const SimSegment segment = SimulateScan(TwoToneWall(dark), lidar, effects, 0.1);
  ASSERT_GE(segment.frames.size(), 3u);
  double expected_lost = 0, variance = 0;
  int lost = 0;
  for (const auto& frame : segment.frames) {
    for (std::size_t i = 0; i < frame.ranges.size(); ++i) {
      const double angle = lidar.angle_first + static_cast<double>(i) * lidar.angle_increment;
      const double clean = 2 / std::cos(angle);
      if (angle < -1e-3) {  // white: never lost, no bias (s = cos / r^2 >> threshold)
        ASSERT_NEAR(frame.ranges[i], clean, 2e-5) << i;
      } else if (angle > 1e-3) {
        const double s = dark * std::cos(angle) / (clean * clean);
        const double p = std::max(0.0, 1 - s / 0.001);
        expected_lost += p;
        variance += p * (1 - p);
        if (std::isnan(frame.ranges[i])) {
          ++lost;
        } else {
          EXPECT_NEAR(frame.ranges[i], clean + 0.01 * (1 - dark), 2e-5) << i;
        }
      }
    }
  }
  EXPECT_GT(expected_lost, 100);
  EXPECT_NEAR(lost, expected_lost, 5 * std::sqrt(variance));
  // Off, the dark half returns everywhere at its clean range.
  const SimSegment off = SimulateScan(TwoToneWall(dark), lidar, FieldEffects{}, 0.1);
  for (float r : off.frames.at(0).ranges) EXPECT_FALSE(std::isnan(r));
  EXPECT_DOUBLE_EQ(ReturnedSignal(0.5, 0.5, 2.0), 0.0625);
}

TEST(FieldEffects, SceneAlbedoNamesItsParts) {
  SceneSpec spec;
  spec.kind = SceneSpec::Kind::kTabletop;
  spec.object = SceneSpec::Object::kTeapot;
  spec.albedo = {{"object", 0.2}, {"room", 0.7}};
  const auto scene = BuildScene(spec);
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  auto caster = RayCaster::Create(*scene);
  ASSERT_TRUE(caster.ok());
  // Down onto the teapot, onto the table beside it, along the room.
  const Eigen::Vector3d top = spec.object_position + Eigen::Vector3d(0, 0, 1);
  EXPECT_NEAR((*caster)->CastHit(top, -Eigen::Vector3d::UnitZ()).albedo, 0.2, 1e-6);
  EXPECT_EQ((*caster)->CastHit(top + Eigen::Vector3d(0, 0.5, 0), -Eigen::Vector3d::UnitZ()).albedo,
            1.0);
  EXPECT_NEAR((*caster)->CastHit(top, Eigen::Vector3d::UnitZ()).albedo, 0.7, 1e-6);
  SceneSpec office;
  office.kind = SceneSpec::Kind::kOffice;
  office.albedo = {{"object", 0.2}};
  const auto failed = BuildScene(office);
  ASSERT_FALSE(failed.ok());
  EXPECT_NE(failed.error().message.find("'object'"), std::string::npos);
}

TEST(FieldEffects, SpeckleIsCorrelatedAlongTheLine) {
  Scene scene;  // a plane at z = 0.8 under the line scanner
  scene.mesh = MakeQuad(Eigen::Vector3d(-5, -5, 0.8), Eigen::Vector3d(10, 0, 0),
                        Eigen::Vector3d(0, 10, 0), 16);
  SensorModel line = LineScanner();
  line.sigma_abs = 0.0002;  // the Wenglor's file
  auto statistics = [&](const FieldEffects& effects, std::vector<double>& correlation) {
    const SimSegment segment = SimulateScan(scene, line, effects, 0.1);
    double sum2 = 0;
    std::vector<double> lagged(correlation.size(), 0.0);
    std::size_t count = 0;
    for (const auto& frame : segment.frames) {
      for (std::size_t i = 0; i < frame.points.size(); ++i) {
        const double r = frame.points[i].z() - 0.8;
        sum2 += r * r;
        ++count;
        for (std::size_t lag = 0; lag < lagged.size(); ++lag) {
          if (i + lag < frame.points.size()) lagged[lag] += r * (frame.points[i + lag].z() - 0.8);
        }
      }
    }
    for (std::size_t lag = 0; lag < lagged.size(); ++lag) correlation[lag] = lagged[lag] / sum2;
    EXPECT_GT(count, 40000u);
    return std::sqrt(sum2 / static_cast<double>(count));
  };
  FieldEffects effects;
  effects.speckle.enabled = true;  // documented default: correlation length 3 points
  std::vector<double> correlation(11);
  EXPECT_NEAR(statistics(effects, correlation), 0.0002, 0.0002 * 0.05);  // the file's sigma
  EXPECT_NEAR(correlation[1], std::exp(-1.0 / 9), 0.05);
  EXPECT_NEAR(correlation[3], std::exp(-1.0), 0.05);
  EXPECT_NEAR(correlation[10], 0, 0.05);
  // Without speckle the same sigma, uncorrelated.
  EXPECT_NEAR(statistics(FieldEffects{}, correlation), 0.0002, 0.0002 * 0.05);
  EXPECT_NEAR(correlation[1], 0, 0.03);
}

// The iiwa of config/robots, upright and still for `hold` seconds in one stationary scan.
struct UprightIiwa {
  RobotModel model;
  ScanPlan plan;
  Scene scene;
  UprightIiwa() {
    auto file = ReadModelFile(Source("config/robots/kuka_lbr_iiwa_r840.yaml"));
    EXPECT_TRUE(file.ok());
    model = file->model;
    PlannedScan scan;
    scan.start.assign(7, 0.0);
    scan.end.assign(7, 0.0);
    plan.scans.push_back(scan);
    scene.spheres.push_back({Eigen::Vector3d(0, 0, 3), 0.5});
  }
};

TEST(FieldEffects, ThermalGrowthLengthensTheLinks) {
  UprightIiwa iiwa;
  auto caster = RayCaster::Create(iiwa.scene);
  ASSERT_TRUE(caster.ok());
  RecordingOptions options;
  options.stationary_hold = 1200;                 // a 20-minute scan: the arm warms up during it
  options.effects.thermal_growth.enabled = true;  // documented default: 23e-6/K, 3 K, 600 s
  const Simulator simulator(iiwa.model, Camera(), **caster, iiwa.plan, options);
  const double end = simulator.Duration();
  const double rise = 3 * (1 - std::exp(-end / 600));
  const double length = 0.36 + 0.42 + 0.40 + 0.126;  // upright: the flange straight above
  EXPECT_NEAR(simulator.TrueSensorPose(0).translation().z(), length, 1e-12);
  EXPECT_NEAR(simulator.TrueSensorPose(end).translation().z(), length * (1 + 23e-6 * rise), 1e-12);
  // The forearm link (A3 to A4 origin, 0.42 m) grows by 25 micrometres by the end.
  std::vector<double> k = ToParameterVector(iiwa.model);
  GrowLinks(options.effects.thermal_growth, end, 7, k.data());
  const std::vector<double> q(7, 0.0);
  const ArmFrames frames = ComputeArmFrames(JointTypes(iiwa.model), k.data(), q.data());
  const double link = (frames.origins[3] - frames.origins[2]).norm();
  EXPECT_NEAR(link - 0.42, 0.42 * 23e-6 * rise, 1e-12);
  EXPECT_GT(link - 0.42, 20e-6);
  EXPECT_LT(link - 0.42, 30e-6);
  EXPECT_EQ(ThermalScale(ThermalGrowthEffect{}, end), 1.0);  // off: nothing grows
}

// The yaw of the point robot's sensor: its one joint's true position.
double Yaw(const Eigen::Isometry3d& pose) {
  return std::atan2(pose.linear()(1, 0), pose.linear()(0, 0));
}

TEST(FieldEffects, BacklashLagSwitchesSignOnReversal) {
  ScanPlan plan;  // a sweep forward, then one back
  PlannedScan forward, backward;
  forward.start = {0.0};
  forward.end = {0.5};
  forward.peak_rate = 1.0;
  backward.start = {0.5};
  backward.end = {0.0};
  backward.peak_rate = 1.0;
  plan.scans = {forward, backward};
  Scene scene;
  scene.spheres.push_back({Eigen::Vector3d(0, 0, 2), 0.5});
  auto caster = RayCaster::Create(scene);
  ASSERT_TRUE(caster.ok());
  RecordingOptions options;
  const Simulator ideal(PointRobot(), Lidar(), **caster, plan, options);
  options.effects.backlash.enabled = true;  // documented default: 0.2 mrad of play
  const Simulator geared(PointRobot(), Lidar(), **caster, plan, options);
  auto lag = [&](double t) { return Yaw(geared.TrueSensorPose(t)) - Yaw(ideal.TrueSensorPose(t)); };
  const SimSegment first = ideal.Segment(0), second = ideal.Segment(1);
  auto seconds = [](std::int64_t us) { return static_cast<double>(us) * 1e-6; };
  const double begin0 = seconds(first.markers[0].stamp_us),
               end0 = seconds(first.markers[1].stamp_us);
  const double begin1 = seconds(second.markers[0].stamp_us),
               end1 = seconds(second.markers[1].stamp_us);
  EXPECT_NEAR(lag(0), 0, 1e-15);  // still: centred
  // Moving forward, the output trails by half the play; still at the reversal it stays there.
  EXPECT_NEAR(lag(0.5 * (begin0 + end0)), -1e-4, 1e-12);
  EXPECT_NEAR(lag(end0 + 0.1), -1e-4, 1e-12);
  EXPECT_NEAR(lag(begin1), -1e-4, 1e-12);
  // Back again: after the input has crossed the play, the lag has the other sign.
  EXPECT_NEAR(lag(0.5 * (begin1 + end1)), 1e-4, 1e-12);
  EXPECT_NEAR(lag(end1 + 0.1), 1e-4, 1e-12);
  // The joint states report the input: the encoders sit on the motor side.
  const SimSegment reported = geared.Segment(0);
  for (std::size_t n = 0; n < reported.joint_states.size(); ++n) {
    EXPECT_NEAR(reported.joint_states[n].positions[0], first.joint_states[n].positions[0], 1e-12);
  }
}

TEST(FieldEffects, ClockDriftIsALatencyGrowingWithTime) {
  ScanPlan plan;  // a LiDAR turning in its own plane in front of a wall at x = 2
  PlannedScan scan;
  scan.start = {-0.3};
  scan.end = {0.3};
  scan.peak_rate = 0.5;
  plan.scans.push_back(scan);
  Scene scene;
  scene.mesh = MakeQuad(Eigen::Vector3d(2, -5, -5), Eigen::Vector3d(0, 10, 0),
                        Eigen::Vector3d(0, 0, 10), 16);
  auto caster = RayCaster::Create(scene);
  ASSERT_TRUE(caster.ok());
  SensorModel lidar = Lidar();
  lidar.angle_first = -1.0;
  lidar.width = 459;
  RecordingOptions options;
  options.latency = 0.01;
  const Simulator ideal(PointRobot(), lidar, **caster, plan, options);
  RecordingOptions drifting = options;
  drifting.effects.timing.enabled = true;
  drifting.effects.timing.clock_drift_ppm = 5000;  // exaggerated: 5 ms per second
  const SimSegment drifted = Simulator(PointRobot(), lidar, **caster, plan, drifting).Segment(0);
  const SimSegment reference = ideal.Segment(0);
  ASSERT_GT(drifted.frames.size(), 10u);
  auto largest_difference = [](const SimFrame& a, const SimFrame& b) {
    double largest = 0;
    for (std::size_t i = 0; i < a.ranges.size(); ++i) {
      largest = std::max(largest, std::abs(static_cast<double>(a.ranges[i] - b.ranges[i])));
    }
    return largest;
  };
  for (std::size_t f : {std::size_t{0}, drifted.frames.size() / 2, drifted.frames.size() - 1}) {
    const SimFrame& frame = drifted.frames[f];
    EXPECT_EQ(frame.stamp_us, reference.frames[f].stamp_us);  // the stamps stay
    // The frame stamped s was measured drift * s earlier: a latency shorter by that much.
    RecordingOptions earlier = options;
    earlier.latency = options.latency - 5000e-6 * static_cast<double>(frame.stamp_us) * 1e-6;
    const SimSegment shifted = Simulator(PointRobot(), lidar, **caster, plan, earlier).Segment(0);
    EXPECT_LT(largest_difference(frame, shifted.frames[f]), 2e-5) << f;
    EXPECT_GT(largest_difference(frame, reference.frames[f]), 1e-3) << f;
  }
}

}  // namespace
}  // namespace selfcal::sim
