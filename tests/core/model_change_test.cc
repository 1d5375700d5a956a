// What changed between two models, class by class, on the iiwa with a sensor mount: a joint's
// lost zero, a moved mount, a changed link, nothing; and a covariance that makes a small change
// insignificant. The same classes on simulated recordings: tests/calib/model_change_test.cc.
#include "core/model/model_change.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/model/joint_offsets.h"
#include "tests/core/test_models.h"

namespace selfcal {
namespace {

constexpr double kDegree = M_PI / 180;

std::vector<std::size_t> Free(const RobotModel& model) {
  std::vector<std::size_t> free;
  for (std::size_t i = 0; i < model.mask.size(); ++i) {
    if (model.mask[i]) free.push_back(i);
  }
  return free;
}

ModelChange Describe(const RobotModel& installed, const RobotModel& calibrated,
                     const Eigen::MatrixXd& covariance = {}) {
  return DescribeModelChange(installed, calibrated, covariance, Free(calibrated));
}

TEST(ModelChange, ALostZeroIsNamedWithItsJointAndDegrees) {
  const RobotModel installed = testing::IiwaWithMount();
  auto calibrated = WithJointOffsets(installed, {0, 0, 0, 0.41 * kDegree, 0, 0, 0});
  ASSERT_TRUE(calibrated);
  const ModelChange change = Describe(installed, *calibrated);
  ASSERT_EQ(change.findings.size(), 1u) << change.Summary();
  EXPECT_EQ(change.findings[0].kind, ChangeKind::kJointZero);
  EXPECT_EQ(change.findings[0].joint, "A4");
  EXPECT_EQ(change.Summary(), "joint A4 zero offset moved 0.410 deg (mastering lost?)");
  // Keeping the installed model would leave the 0.41 deg at the sensor and at the flange.
  EXPECT_GT(change.kept_installed.flange.rms_position_m, 1e-3);
}

TEST(ModelChange, AMovedMountIsABump) {
  const RobotModel installed = testing::IiwaWithMount();
  RobotModel calibrated = installed;
  calibrated.tool.x += 0.002;
  const ModelChange change = Describe(installed, calibrated);
  ASSERT_EQ(change.findings.size(), 1u) << change.Summary();
  EXPECT_EQ(change.findings[0].kind, ChangeKind::kSensorMount);
  EXPECT_EQ(change.Summary(), "sensor mount moved 2.0 mm / 0.00 deg (bumped?)");
  // A turn alone is a bump too (it also shifts the sensor's origin, 0.2 m from the flange).
  RobotModel turned = installed;
  turned.tool.gamma += 0.3 * kDegree;
  const ModelChange turn = Describe(installed, turned);
  ASSERT_EQ(turn.findings.size(), 1u) << turn.Summary();
  EXPECT_EQ(turn.findings[0].kind, ChangeKind::kSensorMount);
  EXPECT_NEAR(turn.fit.mount_turn_rad, 0.3 * kDegree, 1e-9);
  // The flange comparison takes the tool from the truth: the arm itself did not change.
  EXPECT_LT(change.kept_installed.flange.rms_position_m, 1e-9);
  EXPECT_GT(change.kept_installed.sensor.rms_position_m, 1e-3);
}

TEST(ModelChange, ALongerLinkIsGeometryThatOffsetsDoNotExplain) {
  const RobotModel installed = testing::IiwaWithMount();
  RobotModel calibrated = installed;
  calibrated.segments[2].y += 0.002;  // A3 -> A4 two millimetres longer
  const ModelChange change = Describe(installed, calibrated);
  bool geometry = false;
  for (const auto& finding : change.findings) geometry |= finding.kind == ChangeKind::kLinkGeometry;
  EXPECT_TRUE(geometry) << change.Summary();
  EXPECT_GT(change.fit.rms_position_m, 0.3e-3);
}

TEST(ModelChange, TheSameModelHasNoSignificantChange) {
  const RobotModel installed = testing::IiwaWithMount();
  const ModelChange change = Describe(installed, installed);
  EXPECT_TRUE(change.findings.empty());
  EXPECT_EQ(change.Summary(), "no significant change");
  EXPECT_LT(change.kept_installed.sensor.rms_position_m, 1e-9);
}

// A calibration too uncertain to tell 0.05 deg from nothing: the null distribution of the fit
// over its covariance raises the bar above the change; a tight one keeps it.
TEST(ModelChange, AnUncertainCalibrationDoesNotClaimASmallChange) {
  const RobotModel installed = testing::IiwaWithMount();
  auto calibrated = WithJointOffsets(installed, {0, 0, 0, 0.05 * kDegree, 0, 0, 0});
  ASSERT_TRUE(calibrated);
  const auto k = static_cast<Eigen::Index>(Free(*calibrated).size());
  const Eigen::MatrixXd loose = Eigen::MatrixXd::Identity(k, k) * std::pow(0.05 * kDegree, 2);
  const ModelChange uncertain = Describe(installed, *calibrated, loose);
  EXPECT_EQ(uncertain.Summary().find("A4"), std::string::npos) << uncertain.Summary();
  const Eigen::MatrixXd tight = Eigen::MatrixXd::Identity(k, k) * std::pow(1e-4 * kDegree, 2);
  const ModelChange certain = Describe(installed, *calibrated, tight);
  ASSERT_FALSE(certain.findings.empty());
  EXPECT_EQ(certain.findings[0].joint, "A4") << certain.Summary();
  EXPECT_GT(certain.findings[0].std_dev, 0);
  EXPECT_NE(certain.Summary().find("0.050 deg (+-0.000"), std::string::npos) << certain.Summary();
}

// A moved mount's shift and turn each carry their own standard deviation; none without a
// covariance.
TEST(ModelChange, AMovedMountHasTheDeviationsOfItsShiftAndTurn) {
  const RobotModel installed = testing::IiwaWithMount();
  RobotModel calibrated = installed;
  calibrated.tool.x += 0.002;
  calibrated.tool.gamma += 0.3 * kDegree;
  const auto k = static_cast<Eigen::Index>(Free(calibrated).size());
  const Eigen::MatrixXd tight = Eigen::MatrixXd::Identity(k, k) * std::pow(1e-5, 2);
  for (const bool with_covariance : {false, true}) {
    const ModelChange change =
        Describe(installed, calibrated, with_covariance ? tight : Eigen::MatrixXd());
    ASSERT_EQ(change.findings.size(), 1u) << change.Summary();
    const ChangeFinding& mount = change.findings[0];
    EXPECT_EQ(mount.value, change.fit.mount_shift_m);
    EXPECT_EQ(mount.turn_rad, change.fit.mount_turn_rad);
    EXPECT_EQ(mount.std_dev > 0, with_covariance);
    EXPECT_EQ(mount.turn_std_dev_rad > 0, with_covariance);
    EXPECT_LT(mount.turn_std_dev_rad, 0.01 * mount.turn_rad);
  }
}

}  // namespace
}  // namespace selfcal
