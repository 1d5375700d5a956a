// Field effects, each on a known geometry (a plane, a step edge, a corner) with its documented
// magnitude: flying pixels at a step, range bias and incidence noise on a tilted plane, lost
// returns at grazing angles, baseline shadows behind an edge, intrinsics off, gravity
// deflection of a horizontal arm, lagging joint states, the arm and moving things as capsules
// and boxes.
#include "core/sim/field_effects.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/model/kinematics.h"
#include "core/sim/ray_caster.h"
#include "core/sim/simulator.h"
#include "protocols/model_file/model_file.h"
#include "protocols/scenario/effects_file.h"

namespace selfcal::sim {
namespace {

std::string Source(const std::string& relative) {
  const char* root = std::getenv("SELFCAL_SOURCE_DIR");
  return std::string(root ? root : ".") + "/" + relative;
}

// A one-joint robot whose sensor sits at the base origin for q = 0 (identity tool).
RobotModel PointRobot() {
  RobotModel model;
  model.name = "point";
  model.joints.push_back({"J1", JointType::kRevolute, -3, 3, 1, 5});
  model.mask = DefaultMask(model);
  return model;
}

ScanPlan StillPlan() {
  ScanPlan plan;
  PlannedScan scan;
  scan.start = {0.0};
  scan.end = {0.0};
  plan.scans.push_back(scan);
  return plan;
}

// A noise-free Kinect-like camera (NFOV 2x2 binned geometry).
SensorModel Camera() {
  SensorModel m;
  m.kind = SensorLayout::kDepthCamera;
  m.width = 320;
  m.height = 288;
  m.range_min = 0.3;
  m.range_max = 5.46;
  m.intrinsics.fx = 208.5;
  m.intrinsics.fy = 226.0;
  m.intrinsics.cx = 159.5;
  m.intrinsics.cy = 143.5;
  m.frame_period = 1.0 / 30;
  return m;
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

SensorModel LineScanner() {
  SensorModel line;
  line.kind = SensorLayout::kLineScanner;
  line.width = 1280;
  line.range_min = 0.3;
  line.range_max = 1.5;
  line.fan_angle = 0.5;
  line.line_period = 1.0 / 500;
  return line;
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

}  // namespace
}  // namespace selfcal::sim
