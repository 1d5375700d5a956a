// Joint zero offsets from two MCPC models: a model made with known offsets (through the generic
// chain, so that MCPC spreads them over the segments as it would a real remastering error) gives
// them back, the last joint's with the mount; a moved mount is no offset; a changed link length is
// neither and stays in the residual.
#include "core/model/joint_offsets.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/model/chain.h"
#include "core/model/evaluation.h"
#include "core/model/kinematics.h"
#include "tests/core/test_models.h"

namespace selfcal {
namespace {

constexpr auto R = JointType::kRevolute;

// `model` with joint i turned by offsets[i] at its zero (core's WithJointOffsets): the calibrated
// model at q then equals `model` at q + offsets.
RobotModel WithZeroOffsets(const RobotModel& model, const std::vector<double>& offsets) {
  auto converted = WithJointOffsets(model, offsets);
  EXPECT_TRUE(converted) << converted.error().message;
  return *converted;
}

// The UR5 of config/robots/ur5.yaml (three parallel axes); the iiwa is testing::IiwaWithMount().
RobotModel Ur5() {
  RobotModel model;
  model.name = "ur5";
  for (int i = 1; i <= 6; ++i) {
    std::string name = "J";  // append: GCC 12's -Wrestrict misfires on "J" + s
    name.append(std::to_string(i));
    model.joints.push_back({name, R, -3.0, 3.0, 3.0, 5.0});
  }
  constexpr double kQuarter = M_PI / 2;
  model.base = {0, 0, 0, 0, 0, 0.089159};
  model.segments = {{kQuarter, 0, 0, 0},
                    {0, 0, -0.425, 0},
                    {0, 0, -0.39225, 0},
                    {kQuarter, 0, 0, 0.10915},
                    {-kQuarter, 0, 0, -0.09465}};
  model.tool = {0, 0, 0, 0, 0, 0.0823};
  model.mask = DefaultMask(model);
  return model;
}

// The names of the parameters `mask` frees.
std::vector<std::string> FreeNames(const RobotModel& model, const std::vector<bool>& mask) {
  std::vector<std::string> names;
  for (std::size_t i = 0; i < mask.size(); ++i) {
    if (mask[i]) names.push_back(ParameterName(model, i));
  }
  return names;
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

TEST(JointOffsets, WithJointOffsetsIsTheModelAtShiftedJoints) {
  const RobotModel model = testing::RandomModel({R, JointType::kPrismatic, R, R, R, R}, 11);
  const std::vector<double> offsets{0.01, 0.003, -0.02, 0.0087, 0.0, -0.005};
  const auto shifted = WithJointOffsets(model, offsets);
  ASSERT_TRUE(shifted) << shifted.error().message;
  EXPECT_EQ(shifted->mask, model.mask);
  for (const auto& q : RandomConfigurations(model, 20, 3)) {
    std::vector<double> q_plus = q;
    for (std::size_t i = 0; i < q.size(); ++i) q_plus[i] += offsets[i];
    const Transform3<double> expected = ForwardKinematics(model, q_plus);
    const Transform3<double> actual = ForwardKinematics(*shifted, q);
    EXPECT_LT((expected.matrix() - actual.matrix()).norm(), 1e-9);
  }
  EXPECT_FALSE(WithJointOffsets(model, {0.0, 0.0}));
}

TEST(JointOffsets, RemasterFreesTheBetasOfRightAngledAxesAndTheMount) {
  const RobotModel iiwa = testing::IiwaWithMount();
  const auto mask = RemasterMask(iiwa);
  ASSERT_TRUE(mask) << mask.error().message;
  // A1's offset turns arm and scene together (the first segment's beta is not in the mask);
  // A7's is the mount's gamma.
  EXPECT_EQ(FreeNames(iiwa, *mask),
            (std::vector<std::string>{"A2->A3.beta", "A3->A4.beta", "A4->A5.beta", "A5->A6.beta",
                                      "A6->A7.beta", "A7->tool.alpha", "A7->tool.beta",
                                      "A7->tool.gamma", "A7->tool.x", "A7->tool.y", "A7->tool.z"}));
  // A motor swap on A4 (0.5 deg) changes nothing the remastering keeps fixed.
  const RobotModel swapped = WithZeroOffsets(iiwa, {0, 0, 0, 0.5 * M_PI / 180, 0, 0, 0});
  const std::vector<double> k = ToParameterVector(iiwa), k_swapped = ToParameterVector(swapped);
  for (std::size_t i = 0; i < k.size(); ++i) {
    if (!(*mask)[i]) {
      EXPECT_NEAR(k_swapped[i], k[i], 1e-12) << ParameterName(iiwa, i);
    }
  }
  EXPECT_NEAR(k_swapped[SegmentOffset(3) + 1], 0.5 * M_PI / 180 * std::sin(-M_PI / 2), 1e-12);
}

TEST(JointOffsets, RemasterFreesTheTranslationsOfParallelAxes) {
  const RobotModel ur5 = Ur5();
  const auto mask = RemasterMask(ur5);
  ASSERT_TRUE(mask) << mask.error().message;
  // J2's and J3's offsets swing the next axis sideways (y); J4's and J5's are betas.
  EXPECT_EQ(FreeNames(ur5, *mask),
            (std::vector<std::string>{"J2->J3.y", "J3->J4.y", "J4->J5.beta", "J5->J6.beta",
                                      "J6->tool.alpha", "J6->tool.beta", "J6->tool.gamma",
                                      "J6->tool.x", "J6->tool.y", "J6->tool.z"}));
}

TEST(JointOffsets, RemasterStaysWithinTheModelsMask) {
  RobotModel iiwa = testing::IiwaWithMount();
  iiwa.mask[ToolOffset(7) + 3] = false;  // a mount whose x the file does not calibrate
  iiwa.mask[SegmentOffset(3) + 1] = false;
  const auto mask = RemasterMask(iiwa);
  ASSERT_TRUE(mask) << mask.error().message;
  EXPECT_FALSE((*mask)[ToolOffset(7) + 3]);
  EXPECT_FALSE((*mask)[SegmentOffset(3) + 1]);
  EXPECT_TRUE((*mask)[SegmentOffset(2) + 1]);
  iiwa.mask.pop_back();
  EXPECT_FALSE(RemasterMask(iiwa));
}

}  // namespace
}  // namespace selfcal
