// Scan plans: within joint limits, in free space, seeing what they should, and nested (the
// 7-scan plan is the start of the 28-scan plan; validation scans do not depend on the size).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <string>

#include "core/model/kinematics.h"
#include "core/sim/mount.h"
#include "core/sim/scan_plan.h"
#include "protocols/model_file/model_file.h"

namespace selfcal::sim {
namespace {

RobotModel Iiwa(const SensorMount& mount) {
  const char* root = std::getenv("SELFCAL_SOURCE_DIR");
  const std::string path =
      std::string(root ? root : ".") + "/config/robots/kuka_lbr_iiwa_r840.yaml";
  auto file = ReadModelFile(path);
  EXPECT_TRUE(file.ok()) << (file.ok() ? "" : file.error().message);
  return WithSensorMount(file->model, mount);
}

void ExpectWithinLimits(const RobotModel& model, const std::vector<double>& q, double margin) {
  ASSERT_EQ(q.size(), model.JointCount());
  for (std::size_t j = 0; j < q.size(); ++j) {
    EXPECT_GE(q[j], model.joints[j].lower + margin - 1e-9) << "joint " << j;
    EXPECT_LE(q[j], model.joints[j].upper - margin + 1e-9) << "joint " << j;
  }
}

SensorModel Camera() {
  SensorModel m;
  m.kind = SensorLayout::kDepthCamera;
  m.width = 80;
  m.height = 72;
  m.range_min = 0.5;
  m.range_max = 5.46;
  m.intrinsics.fx = 52;
  m.intrinsics.fy = 56.5;
  m.intrinsics.cx = 39.5;
  m.intrinsics.cy = 35.5;
  m.frame_period = 1.0 / 30;
  return m;
}

TEST(ScanPlan, StationaryViewsLookAtTheTargetFromWithinRange) {
  const RobotModel nominal = Iiwa({0, -0.045, 0.075, 0, 0, 0});
  const Scene scene = MakeCornerScene();
  PlanOptions options;
  options.kind = PlanOptions::Kind::kStationaryViews;
  options.fit_scans = 14;
  options.validation_scans = 7;
  options.view.target = Eigen::Vector3d(1.0, 0.25, 0.2);
  options.view.target_jitter = 0.05;
  options.view.distance_min = 0.8;
  options.view.distance_max = 1.1;
  options.view.elevation_min = 0.25;
  options.view.elevation_max = 0.9;
  options.view.azimuth_min = -0.8;
  options.view.azimuth_max = 0.8;
  auto plan = MakeScanPlan(nominal, Camera(), scene, options);
  ASSERT_TRUE(plan.ok()) << plan.error().message;
  ASSERT_EQ(plan->scans.size(), 21u);
  for (std::size_t k = 0; k < plan->scans.size(); ++k) {
    const auto& scan = plan->scans[k];
    EXPECT_EQ(scan.purpose, k < 14 ? ScanPurpose::kFit : ScanPurpose::kValidation);
    ExpectWithinLimits(nominal, scan.start, options.limit_margin);
    EXPECT_EQ(scan.start, scan.end);
    const Eigen::Isometry3d T = ForwardKinematics(nominal, scan.start);
    const Eigen::Vector3d to_target = options.view.target - T.translation();
    // The optical axis points at the (jittered) target, from the requested distance.
    EXPECT_GT(T.linear().col(2).dot(to_target.normalized()), std::cos(0.15)) << "scan " << k;
    EXPECT_GT(to_target.norm(), options.view.distance_min - 0.1);
    EXPECT_LT(to_target.norm(), options.view.distance_max + 0.1);
    EXPECT_TRUE(scene.IsFree(T.translation(), options.free_margin - 1e-6));
  }
  // Nested: the first 7 fit scans of a 7-scan plan are those of the 14-scan plan, and the
  // validation scans are the same.
  options.fit_scans = 7;
  auto small = MakeScanPlan(nominal, Camera(), scene, options);
  ASSERT_TRUE(small.ok());
  for (int k = 0; k < 7; ++k)
    EXPECT_EQ(small->scans[static_cast<std::size_t>(k)].start,
              plan->scans[static_cast<std::size_t>(k)].start);
  for (int v = 0; v < 7; ++v)
    EXPECT_EQ(small->scans[static_cast<std::size_t>(7 + v)].start,
              plan->scans[static_cast<std::size_t>(14 + v)].start);
}

TEST(ScanPlan, LidarSweepsTurnOneAxisByHalfATurnWithinLimits) {
  SensorMount mount{0.0, 0.0, 0.09, 0.0, -std::numbers::pi / 2, 0.0};
  const RobotModel nominal = Iiwa(mount);
  const Scene scene = MakeOfficeScene();
  SensorModel lidar;
  lidar.kind = SensorLayout::kRotatingLidar;
  lidar.angle_increment = 2 * std::numbers::pi / 1440;
  lidar.rotation_period = 0.025;
  PlanOptions options;
  options.kind = PlanOptions::Kind::kLidarSweeps;
  options.fit_scans = 28;
  options.validation_scans = 7;
  options.joint_speed = LidarJointSpeed(lidar, 1.0);
  EXPECT_NEAR(options.joint_speed, 10 * std::numbers::pi / 180, 1e-12);  // 10 deg/s
  auto plan = MakeScanPlan(nominal, lidar, scene, options);
  ASSERT_TRUE(plan.ok()) << plan.error().message;
  ASSERT_EQ(plan->scans.size(), 35u);
  for (const auto& scan : plan->scans) {
    ExpectWithinLimits(nominal, scan.start, options.limit_margin);
    ExpectWithinLimits(nominal, scan.end, options.limit_margin);
    ASSERT_GE(scan.moving_joint, 0);
    for (std::size_t j = 0; j < scan.start.size(); ++j) {
      const double moved = std::abs(scan.end[j] - scan.start[j]);
      EXPECT_NEAR(moved, static_cast<int>(j) == scan.moving_joint ? std::numbers::pi : 0.0, 1e-12);
    }
    // 180 degrees at 10 deg/s: the path rate is 1 / 18 s.
    EXPECT_NEAR(scan.peak_rate, 1.0 / 18, 1e-9);
  }
}

TEST(ScanPlan, LineSweepsMoveAcrossTheObject) {
  const RobotModel nominal = Iiwa({0, -0.05, 0.06, 0, 0, 0});
  SceneSpec spec;
  spec.kind = SceneSpec::Kind::kTabletop;
  spec.object = SceneSpec::Object::kTeapot;
  spec.object_size = 0.15;
  auto scene = BuildScene(spec);
  ASSERT_TRUE(scene.ok());
  SensorModel line;
  line.kind = SensorLayout::kLineScanner;
  line.range_min = 0.3;
  line.range_max = 1.5;
  PlanOptions options;
  options.kind = PlanOptions::Kind::kLineSweeps;
  options.fit_scans = 7;
  options.validation_scans = 2;
  options.view.target = scene->focus;
  options.view.distance_min = 0.45;
  options.view.distance_max = 0.6;
  options.sweep_length = 0.25;
  options.sweep_speed = 0.1;
  auto plan = MakeScanPlan(nominal, line, *scene, options);
  ASSERT_TRUE(plan.ok()) << plan.error().message;
  for (const auto& scan : plan->scans) {
    ExpectWithinLimits(nominal, scan.start, options.limit_margin);
    ExpectWithinLimits(nominal, scan.end, options.limit_margin);
    const Eigen::Isometry3d a = ForwardKinematics(nominal, scan.start);
    const Eigen::Isometry3d b = ForwardKinematics(nominal, scan.end);
    // The sensor moves by the sweep length along its own y axis, keeping its orientation.
    EXPECT_NEAR((b.translation() - a.translation()).norm(), 0.25, 1e-3);
    EXPECT_GT((b.translation() - a.translation()).normalized().dot(a.linear().col(1)), 0.999);
    EXPECT_LT(Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle(), 1e-3);
    EXPECT_NEAR(scan.peak_rate, 0.1 / 0.25, 1e-12);
  }
}

TEST(ScanPlan, ViewsMustBeWithinTheSensorsRange) {
  const RobotModel nominal = Iiwa({0, 0, 0.07, 0, 0, 0});
  PlanOptions options;
  options.view.target = Eigen::Vector3d(0.9, 0.2, 0.2);
  options.view.distance_min = 0.3;  // the camera sees nothing closer than 0.5 m
  options.view.distance_max = 0.6;
  auto plan = MakeScanPlan(nominal, Camera(), MakeCornerScene(), options);
  ASSERT_FALSE(plan.ok());
  EXPECT_NE(plan.error().message.find("view range"), std::string::npos) << plan.error().message;
}

TEST(ScanPlan, ImpossibleViewsNameTheScan) {
  const RobotModel nominal = Iiwa({0, 0, 0.07, 0, 0, 0});
  PlanOptions options;
  options.kind = PlanOptions::Kind::kStationaryViews;
  options.view.target = Eigen::Vector3d(5.0, 0, 0);  // far out of reach
  options.max_attempts = 5;
  auto plan = MakeScanPlan(nominal, Camera(), MakeCornerScene(), options);
  ASSERT_FALSE(plan.ok());
  EXPECT_NE(plan.error().message.find("fit scan 0"), std::string::npos) << plan.error().message;
}

}  // namespace
}  // namespace selfcal::sim
