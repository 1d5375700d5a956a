// Joint zero offsets from two MCPC models: a model made with known offsets (through the generic
// chain, so that MCPC spreads them over the segments as it would a real remastering error) gives
// them back, the last joint's with the mount; a moved mount is no offset; a changed link length is
// neither and stays in the residual.
#include "core/model/joint_offsets.h"

#include <gtest/gtest.h>

#include "core/model/chain.h"
#include "core/model/kinematics.h"
#include "tests/core/test_models.h"

namespace selfcal {
namespace {

constexpr auto R = JointType::kRevolute;

// `model` with joint i turned by offsets[i] at its zero: F_{i-1} * rot_z(offset), then back to
// MCPC. The calibrated model at q then equals `model` at q + offsets.
RobotModel WithZeroOffsets(const RobotModel& model, const std::vector<double>& offsets) {
  GenericChain chain = McpcToChain(model);
  for (std::size_t i = 0; i < offsets.size(); ++i) {
    chain.fixed[i] = chain.fixed[i] * Eigen::AngleAxisd(offsets[i], Eigen::Vector3d::UnitZ());
  }
  auto converted = ChainToMcpc(chain);
  EXPECT_TRUE(converted) << converted.error().message;
  return converted->model;
}

TEST(JointOffsets, IdenticalModelsHaveNone) {
  const RobotModel model = testing::RandomModel({R, R, R, R, R, R, R}, 3);
  const JointOffsetFit fit = FitJointOffsets(model, model);
  ASSERT_EQ(fit.offsets.size(), 7u);
  for (double offset : fit.offsets) EXPECT_NEAR(offset, 0.0, 1e-12);
  EXPECT_LT(fit.rms_position_m, 1e-12);
  EXPECT_EQ(fit.samples, 200u);
}

TEST(JointOffsets, KnownOffsetsComeBackPerAxis) {
  const RobotModel nominal = testing::RandomModel({R, R, R, R, R, R, R}, 5);
  const std::vector<double> offsets{0.0, 0.0087, 0.0, -0.0031, 0.0, 0.0021, 0.0};
  const RobotModel calibrated = WithZeroOffsets(nominal, offsets);
  // Not trivially the same numbers: MCPC moved the offsets into other parameters.
  EXPECT_NE(ToParameterVector(calibrated), ToParameterVector(nominal));
  const JointOffsetFit fit = FitJointOffsets(nominal, calibrated);
  for (std::size_t i = 0; i < offsets.size(); ++i) {
    EXPECT_NEAR(fit.offsets[i], offsets[i], 1e-9) << "joint " << i + 1;
  }
  EXPECT_LT(fit.mount_turn_rad, 1e-9);
  EXPECT_LT(fit.rms_position_m, 1e-9);
  EXPECT_LT(fit.rms_orientation_rad, 1e-9);
}

TEST(JointOffsets, TheLastJointsOffsetIsTheMountTurningAboutIt) {
  const RobotModel nominal = testing::RandomModel({R, R, R, R, R, R, R}, 6);
  const RobotModel calibrated = WithZeroOffsets(nominal, {0, 0, 0, 0, 0, 0, 0.004});
  const JointOffsetFit fit = FitJointOffsets(nominal, calibrated);
  for (double offset : fit.offsets) EXPECT_NEAR(offset, 0.0, 1e-9);
  EXPECT_NEAR(fit.mount_turn_rad, 0.004, 1e-9);
  EXPECT_LT(fit.rms_position_m, 1e-9);
}

TEST(JointOffsets, AMovedMountIsNoOffset) {
  const RobotModel nominal = testing::RandomModel({R, R, R, R, R, R, R}, 8);
  RobotModel calibrated = nominal;
  calibrated.tool.x += 0.002;
  calibrated.tool.beta += 0.003;
  const JointOffsetFit fit = FitJointOffsets(nominal, calibrated);
  for (double offset : fit.offsets) EXPECT_NEAR(offset, 0.0, 1e-9);
  EXPECT_GT(fit.mount_shift_m, 1e-3);
  EXPECT_LT(fit.rms_position_m, 1e-9);
}

TEST(JointOffsets, ALongerLinkIsNoOffsetAndStaysInTheResidual) {
  const RobotModel nominal = testing::RandomModel({R, R, R, R, R, R, R}, 7);
  RobotModel calibrated = nominal;
  calibrated.segments[2].x += 0.002;  // 2 mm longer
  const JointOffsetFit fit = FitJointOffsets(nominal, calibrated);
  EXPECT_GT(fit.rms_position_m, 2e-4);
}

}  // namespace
}  // namespace selfcal
