#include "core/model/robot_model.h"

#include <gtest/gtest.h>

#include <random>

#include "core/model/kinematics.h"

namespace selfcal {
namespace {

RobotModel ThreeJointModel() {
  RobotModel model;
  model.name = "test";
  model.joints = {{"J1", JointType::kRevolute, -3, 3, 1, 1},
                  {"J2", JointType::kPrismatic, 0, 1, 1, 1},
                  {"J3", JointType::kRevolute, -3, 3, 1, 1}};
  model.base = {0.1, -0.2, 0.3, 0.4, -0.5, 0.6};
  model.segments = {{0.7, -0.8, 0.9, -1.0}, {1.1, 1.2, 1.3, 1.4}};
  model.tool = {-1.5, 1.6, -1.7, 1.8, -1.9, 2.0};
  model.mask = DefaultMask(model);
  return model;
}

TEST(RobotModel, ParameterVectorRoundTripsAndNamesEveryEntry) {
  RobotModel model = ThreeJointModel();
  const auto k = ToParameterVector(model);
  ASSERT_EQ(k.size(), 20u);  // 6 + 2 * 4 + 6
  EXPECT_DOUBLE_EQ(k[SegmentOffset(1) + 3], 1.4);
  EXPECT_DOUBLE_EQ(k[ToolOffset(3) + 2], -1.7);
  RobotModel copy = model;
  std::vector<double> changed = k;
  for (auto& v : changed) v += 1;
  FromParameterVector(changed, copy);
  EXPECT_DOUBLE_EQ(copy.segments[0].y, 0.0);
  EXPECT_DOUBLE_EQ(copy.tool.z, 3.0);
  EXPECT_EQ(ParameterName(model, 0), "base.alpha");
  EXPECT_EQ(ParameterName(model, SegmentOffset(1) + 1), "J2->J3.beta");
  EXPECT_EQ(ParameterName(model, ToolOffset(3) + 5), "J3->tool.z");
  EXPECT_TRUE(IsTranslationParameter(model, SegmentOffset(0) + 2));
  EXPECT_FALSE(IsTranslationParameter(model, ToolOffset(3) + 2));
}

TEST(RobotModel, DefaultMaskIsThePapers) {
  RobotModel model = ThreeJointModel();
  const auto mask = DefaultMask(model);
  // Base: nothing. First segment (to a prismatic joint): alpha only. Second: all four. Tool: six.
  for (std::size_t i = 0; i < 6; ++i) EXPECT_FALSE(mask[i]);
  EXPECT_EQ((std::vector<bool>(mask.begin() + 6, mask.begin() + 10)),
            (std::vector<bool>{true, false, false, false}));
  EXPECT_EQ((std::vector<bool>(mask.begin() + 10, mask.begin() + 14)),
            (std::vector<bool>{true, true, true, true}));
  for (std::size_t i = 14; i < 20; ++i) EXPECT_TRUE(mask[i]);
}

// An independent composition of the paper's formulas with 4x4 matrices.
Eigen::Matrix4d Rx(double a) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m(1, 1) = std::cos(a);
  m(1, 2) = -std::sin(a);
  m(2, 1) = std::sin(a);
  m(2, 2) = std::cos(a);
  return m;
}
Eigen::Matrix4d Ry(double a) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m(0, 0) = std::cos(a);
  m(0, 2) = std::sin(a);
  m(2, 0) = -std::sin(a);
  m(2, 2) = std::cos(a);
  return m;
}
Eigen::Matrix4d Rz(double a) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m(0, 0) = std::cos(a);
  m(0, 1) = -std::sin(a);
  m(1, 0) = std::sin(a);
  m(1, 1) = std::cos(a);
  return m;
}
Eigen::Matrix4d T(double x, double y, double z) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m(0, 3) = x;
  m(1, 3) = y;
  m(2, 3) = z;
  return m;
}

TEST(Kinematics, MatchesTheMcpcProductOfThePaper) {
  const RobotModel model = ThreeJointModel();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-2, 2);
  for (int trial = 0; trial < 20; ++trial) {
    const std::vector<double> j = {u(rng), 0.5 * (u(rng) + 2) / 2, u(rng)};
    const auto& b = model.base;
    const auto& s1 = model.segments[0];
    const auto& s2 = model.segments[1];
    const auto& t = model.tool;
    const Eigen::Matrix4d expected =
        Rx(b.alpha) * Ry(b.beta) * Rz(b.gamma) * T(b.x, b.y, b.z) * Rz(j[0]) * Rx(s1.alpha) *
        Ry(s1.beta) * T(s1.x, s1.y, 0) * T(0, 0, j[1]) * Rx(s2.alpha) * Ry(s2.beta) *
        T(s2.x, s2.y, 0) * Rz(j[2]) * Rx(t.alpha) * Ry(t.beta) * Rz(t.gamma) * T(t.x, t.y, t.z);
    const Eigen::Matrix4d actual = ForwardKinematics(model, j).matrix();
    EXPECT_LT((actual - expected).cwiseAbs().maxCoeff(), 1e-12) << "trial " << trial;
  }
}

// Prismatic joints first, last and back to back, against the same independent composition.
TEST(Kinematics, PrismaticJointsAnywhereMatchThePapersProduct) {
  RobotModel model;
  model.name = "prismatic";
  model.joints = {{"P1", JointType::kPrismatic, -0.5, 0.5, 1, 1},
                  {"P2", JointType::kPrismatic, -0.5, 0.5, 1, 1},
                  {"R3", JointType::kRevolute, -3, 3, 1, 1},
                  {"P4", JointType::kPrismatic, -0.5, 0.5, 1, 1}};
  model.base = {0.2, 0.1, -0.3, 0.05, 0.4, -0.2};
  model.segments = {{0.3, -0.6, 0.0, 0.0}, {1.0, 0.2, 0.0, 0.0}, {-0.7, 0.4, 0.0, 0.0}};
  model.tool = {0.5, -0.4, 1.1, 0.02, -0.03, 0.15};
  model.mask = DefaultMask(model);
  // Segments before a prismatic joint carry no x and y: the default mask leaves them out.
  EXPECT_FALSE(model.mask[SegmentOffset(0) + 2]);
  EXPECT_FALSE(model.mask[SegmentOffset(2) + 3]);
  EXPECT_TRUE(model.mask[SegmentOffset(2) + 1]);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  for (int trial = 0; trial < 20; ++trial) {
    const std::vector<double> j = {u(rng), u(rng), 6 * u(rng), u(rng)};
    const auto& b = model.base;
    const auto& s = model.segments;
    const auto& t = model.tool;
    const Eigen::Matrix4d expected =
        Rx(b.alpha) * Ry(b.beta) * Rz(b.gamma) * T(b.x, b.y, b.z) * T(0, 0, j[0]) * Rx(s[0].alpha) *
        Ry(s[0].beta) * T(s[0].x, s[0].y, 0) * T(0, 0, j[1]) * Rx(s[1].alpha) * Ry(s[1].beta) *
        T(s[1].x, s[1].y, 0) * Rz(j[2]) * Rx(s[2].alpha) * Ry(s[2].beta) * T(s[2].x, s[2].y, 0) *
        T(0, 0, j[3]) * Rx(t.alpha) * Ry(t.beta) * Rz(t.gamma) * T(t.x, t.y, t.z);
    const Eigen::Matrix4d actual = ForwardKinematics(model, j).matrix();
    EXPECT_LT((actual - expected).cwiseAbs().maxCoeff(), 1e-12) << "trial " << trial;
  }
}

TEST(RobotModel, ConsistencyNamesTheProblem) {
  RobotModel model = ThreeJointModel();
  EXPECT_EQ(CheckConsistency(model), "");
  model.segments.pop_back();
  EXPECT_NE(CheckConsistency(model).find("segments"), std::string::npos);
}

}  // namespace
}  // namespace selfcal
