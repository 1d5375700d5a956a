// Model comparison on known perturbations: the numbers are known in closed form.
#include "core/model/evaluation.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/core/test_models.h"

namespace selfcal {
namespace {

constexpr auto R = JointType::kRevolute;

RobotModel Truth() { return testing::RandomModel({R, R, R, R, R, R, R}, 11); }

TEST(Evaluation, IdenticalModelsHaveNoError) {
  const ModelComparison c = CompareModels(Truth(), Truth(), 200, 1);
  EXPECT_EQ(c.samples, 200u);
  EXPECT_LT(c.sensor.max_position_m, 1e-12);
  EXPECT_LT(c.sensor.max_orientation_rad, 1e-7);
  EXPECT_LT(c.flange.max_position_m, 1e-12);
}

TEST(Evaluation, ToolOffsetOf10mmIs10mmAtTheSensorAndNothingAtTheFlange) {
  RobotModel model = Truth();
  // A translation in the tool frame moves the sensor by exactly 10 mm in every configuration.
  model.tool.x += 0.006;
  model.tool.y -= 0.008;
  const ModelComparison c = CompareModels(Truth(), model, 500, 2);
  EXPECT_NEAR(c.sensor.rms_position_m, 0.010, 1e-12);
  EXPECT_NEAR(c.sensor.max_position_m, 0.010, 1e-12);
  EXPECT_LT(c.sensor.max_orientation_rad, 1e-7);
  EXPECT_LT(c.flange.max_position_m, 1e-12);
  EXPECT_LT(c.flange.max_orientation_rad, 1e-7);
}

TEST(Evaluation, ToolRotationGivesItsAngleEverywhere) {
  RobotModel model = Truth();
  model.tool.gamma += 0.01;  // about the tool's own z after alpha and beta
  const ModelComparison c = CompareModels(Truth(), model, 300, 3);
  EXPECT_NEAR(c.sensor.rms_orientation_rad, 0.01, 1e-9);
  EXPECT_NEAR(c.sensor.max_orientation_rad, 0.01, 1e-9);
  EXPECT_LT(c.flange.max_orientation_rad, 1e-7);
}

TEST(Evaluation, BaseAndUnobservableParametersComeFromTheTruthAtTheFlange) {
  RobotModel model = Truth();
  model.base.z += 0.005;         // shifts every pose by 5 mm (base frame translation)
  model.segments[0].y += 0.003;  // J1 -> J2 y: masked out by default
  const ModelComparison c = CompareModels(Truth(), model, 300, 4);
  EXPECT_GT(c.sensor.rms_position_m, 0.001);
  EXPECT_LT(c.flange.max_position_m, 1e-12);
}

TEST(Evaluation, ASegmentErrorShowsInBothComparisons) {
  RobotModel model = Truth();
  model.segments[3].alpha += 0.002;
  const ModelComparison c = CompareModels(Truth(), model, 300, 5);
  EXPECT_GT(c.sensor.rms_position_m, 1e-4);
  EXPECT_NEAR(c.flange.rms_position_m, c.sensor.rms_position_m, 1e-12);
  EXPECT_NEAR(c.sensor.max_orientation_rad, 0.002, 1e-9);  // a rotation error is the same angle
}

TEST(Evaluation, SameSeedSameNumbersAndConfigurationsWithinLimits) {
  RobotModel model = Truth();
  model.segments[2].x += 0.01;
  const ModelComparison a = CompareModels(Truth(), model, 100, 7);
  const ModelComparison b = CompareModels(Truth(), model, 100, 7);
  EXPECT_EQ(a.sensor.rms_position_m, b.sensor.rms_position_m);
  EXPECT_EQ(a.flange.max_orientation_rad, b.flange.max_orientation_rad);
  for (const auto& q : RandomConfigurations(model, 100, 7)) {
    for (std::size_t i = 0; i < q.size(); ++i) {
      EXPECT_GE(q[i], model.joints[i].lower);
      EXPECT_LE(q[i], model.joints[i].upper);
    }
  }
}

TEST(Evaluation, SensorPoseErrorIsTheComparisonsSensorPartOnAnyConfigurations) {
  RobotModel model = Truth();
  model.tool.x += 0.006;
  model.tool.y -= 0.008;  // 10 mm at the sensor in every configuration
  model.segments[1].beta += 0.003;
  const ModelComparison c = CompareModels(Truth(), model, 300, 8);
  const PoseErrorStats e = SensorPoseError(Truth(), model, 300, 8);
  EXPECT_EQ(e.rms_position_m, c.sensor.rms_position_m);
  EXPECT_EQ(e.max_position_m, c.sensor.max_position_m);
  EXPECT_EQ(e.rms_orientation_rad, c.sensor.rms_orientation_rad);
  EXPECT_EQ(e.max_orientation_rad, c.sensor.max_orientation_rad);

  RobotModel tool_only = Truth();
  tool_only.tool.x += 0.006;
  tool_only.tool.y -= 0.008;
  const std::vector<std::vector<double>> configurations = {std::vector<double>(7, 0.0),
                                                           {0.3, -1.2, 2.0, 0.1, -0.4, 1.1, 2.4}};
  const PoseErrorStats given = SensorPoseError(Truth(), tool_only, configurations);
  EXPECT_NEAR(given.rms_position_m, 0.010, 1e-12);
  EXPECT_NEAR(given.max_position_m, 0.010, 1e-12);
  EXPECT_LT(given.max_orientation_rad, 1e-7);
  const PoseErrorStats none = SensorPoseError(Truth(), tool_only, {});
  EXPECT_EQ(none.rms_position_m, 0.0);
  EXPECT_EQ(none.max_orientation_rad, 0.0);
}

TEST(Evaluation, IncomparableModelsAreNamed) {
  RobotModel other = testing::RandomModel({R, R, R}, 1);
  EXPECT_NE(CheckComparable(Truth(), other).find("joints"), std::string::npos);
  RobotModel renamed = Truth();
  renamed.joints[2].name = std::string(1, 'X');  // not = "X": GCC 12 -Wrestrict misfires
  EXPECT_NE(CheckComparable(Truth(), renamed).find("'X'"), std::string::npos);
  EXPECT_EQ(CheckComparable(Truth(), Truth()), "");
}

TEST(Evaluation, LinkChangesNameTheLinkThatMovedAndHowFar) {
  RobotModel model = Truth();
  model.segments[3].alpha += 0.002;  // J4->J5 turns (and its x, y turn with it)
  model.tool.x += 0.003;             // the tool moves along its rotated x: 3 mm
  const std::vector<LinkChange> changes = LinkChanges(Truth(), model);
  ASSERT_EQ(changes.size(), 8u);  // base, 6 segments, tool
  EXPECT_EQ(changes[0].link, "base");
  EXPECT_EQ(changes[4].link, "J4->J5");
  EXPECT_EQ(changes[7].link, "J7->tool");
  for (std::size_t i = 0; i < changes.size(); ++i) {
    EXPECT_NEAR(changes[i].turn_rad, i == 4 ? 0.002 : 0.0, 1e-9) << changes[i].link;
  }
  EXPECT_NEAR(changes[7].shift_m, 0.003, 1e-12);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_EQ(changes[i].shift_m, 0.0) << changes[i].link;
}

}  // namespace
}  // namespace selfcal
