// Generic chains and DH tables to MCPC: same forward kinematics for every configuration, and the
// canonical form the paper's mask expects.
#include "core/model/chain.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "core/model/kinematics.h"
#include "tests/core/test_models.h"

namespace selfcal {
namespace {

constexpr auto R = JointType::kRevolute;
constexpr auto P = JointType::kPrismatic;
constexpr double kPi = std::numbers::pi;

Eigen::Isometry3d RandomIsometry(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::Quaterniond q(u(rng), u(rng), u(rng), u(rng));
  q.normalize();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.toRotationMatrix();
  T.translation() = 0.5 * Eigen::Vector3d(u(rng), u(rng), u(rng));
  return T;
}

JointSpec Joint(std::size_t i, JointType type) {
  std::string name = "J";
  name.append(std::to_string(i + 1));
  return type == R ? JointSpec{name, R, -2.8, 2.8, 1, 1} : JointSpec{name, P, -0.3, 0.5, 1, 1};
}

GenericChain RandomChain(const std::vector<JointType>& types, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  GenericChain chain;
  chain.name = "random";
  chain.fixed.push_back(RandomIsometry(rng));
  for (std::size_t i = 0; i < types.size(); ++i) {
    chain.joints.push_back({Joint(i, types[i]), Eigen::Vector3d(u(rng), u(rng), u(rng)) * 3});
    chain.fixed.push_back(RandomIsometry(rng));
  }
  return chain;
}

// Largest position and rotation-matrix difference of FK over random configurations.
void ExpectSameKinematics(const GenericChain& chain, const RobotModel& model, unsigned seed,
                          double tolerance = 1e-12) {
  ASSERT_EQ(CheckConsistency(model), "");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  double worst_position = 0, worst_rotation = 0;
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<double> q;
    for (const auto& joint : model.joints) {
      q.push_back(joint.lower + unit(rng) * (joint.upper - joint.lower));
    }
    const Eigen::Isometry3d expected = ChainForwardKinematics(chain, q);
    const Eigen::Isometry3d actual = ForwardKinematics(model, q);
    worst_position =
        std::max(worst_position, (expected.translation() - actual.translation()).norm());
    worst_rotation =
        std::max(worst_rotation, (expected.linear() - actual.linear()).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst_position, tolerance);
  EXPECT_LT(worst_rotation, tolerance);
}

TEST(Chain, RandomChainsConvertExactly) {
  const std::vector<std::vector<JointType>> mixes = {
      {R}, {P}, {R, R}, {R, P, R}, {P, P, R, R}, {R, R, R, R, R, R, R}, {R, P, P, P, R, R}};
  unsigned seed = 1;
  for (const auto& types : mixes) {
    const GenericChain chain = RandomChain(types, seed);
    const auto converted = ChainToMcpc(chain);
    ASSERT_TRUE(converted.ok()) << converted.error().message;
    ExpectSameKinematics(chain, converted->model, seed + 1000);
    ++seed;
  }
}

TEST(Chain, FirstSegmentHoldsNothingTheMaskLeavesOut) {
  for (unsigned seed = 20; seed < 30; ++seed) {
    const auto converted = ChainToMcpc(RandomChain({R, R, R, R}, seed));
    ASSERT_TRUE(converted.ok());
    const SegmentParams& first = converted->model.segments[0];
    EXPECT_NEAR(first.beta, 0, 1e-12);
    EXPECT_NEAR(first.y, 0, 1e-12);
    EXPECT_GT(std::abs(std::sin(first.alpha)), 1e-6);  // the axes are not parallel
  }
}

TEST(Chain, PrismaticSuccessorsHaveNoShift) {
  const auto converted = ChainToMcpc(RandomChain({R, P, P, R, P}, 40));
  ASSERT_TRUE(converted.ok());
  for (std::size_t i = 0; i < converted->model.segments.size(); ++i) {
    if (converted->model.joints[i + 1].type == P) {
      EXPECT_EQ(converted->model.segments[i].x, 0.0);
      EXPECT_EQ(converted->model.segments[i].y, 0.0);
    }
  }
  ExpectSameKinematics(RandomChain({R, P, P, R, P}, 40), converted->model, 41);
}

// A planar arm: every axis parallel, where DH is discontinuous and MCPC is not.
TEST(Chain, ParallelAxesGiveZeroAnglesAndTheLinkLengths) {
  GenericChain chain;
  chain.name = "planar";
  chain.fixed.push_back(Eigen::Isometry3d(Eigen::Translation3d(0.1, 0.2, 0.3)));
  const double lengths[] = {0.4, 0.3, 0.2};
  for (std::size_t i = 0; i < 3; ++i) {
    chain.joints.push_back({Joint(i, R), Eigen::Vector3d::UnitZ()});
    // Each next joint 'lengths[i]' along x and 0.05 up (absorbed along the axis).
    chain.fixed.push_back(Eigen::Isometry3d(Eigen::Translation3d(lengths[i], 0, 0.05)));
  }
  const auto converted = ChainToMcpc(chain);
  ASSERT_TRUE(converted.ok());
  const RobotModel& model = converted->model;
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_NEAR(model.segments[i].alpha, 0, 1e-15);
    EXPECT_NEAR(model.segments[i].beta, 0, 1e-15);
    EXPECT_NEAR(model.segments[i].x, lengths[i], 1e-15);
    EXPECT_NEAR(model.segments[i].y, 0, 1e-15);
  }
  // The offsets along z went to the tool (0.05 twice) and its own 0.05.
  EXPECT_NEAR(model.tool.z, 0.15, 1e-15);
  EXPECT_NEAR(model.tool.x, 0.2, 1e-15);
  ExpectSameKinematics(chain, model, 3);
}

TEST(Chain, NearlyParallelFirstAxesStayExactAndSayWhy) {
  GenericChain chain = RandomChain({R, R, R}, 50);
  // Axis 2 tilted 1e-4 rad toward its 0.3 m offset from axis 1: the lines cross 3 km away.
  chain.fixed[1] = Eigen::Isometry3d(Eigen::Translation3d(0.3, 0, 0.1));
  chain.joints[0].axis = Eigen::Vector3d::UnitZ();
  chain.joints[1].axis = Eigen::Vector3d(1e-4, 0, 1).normalized();
  const auto converted = ChainToMcpc(chain);
  ASSERT_TRUE(converted.ok());
  ASSERT_EQ(converted->notes.size(), 1u);
  EXPECT_NE(converted->notes[0].find("nearly parallel"), std::string::npos);
  ExpectSameKinematics(chain, converted->model, 51);
}

TEST(Chain, AxisAlongTheCurrentXIsTheMcpcSingularityAndStillExact) {
  GenericChain chain;
  chain.name = "singular";
  chain.fixed.push_back(Eigen::Isometry3d::Identity());
  chain.joints = {{Joint(0, R), Eigen::Vector3d::UnitZ()},
                  {Joint(1, R), Eigen::Vector3d::UnitX()},
                  {Joint(2, R), Eigen::Vector3d::UnitZ()}};
  // Z_1 has x = a_1 x a_2 = base y, Z_2 keeps that x; joint 3's axis is base y: beta = 90 deg.
  chain.fixed.push_back(Eigen::Isometry3d(Eigen::Translation3d(0, 0, 0.3)));
  Eigen::Isometry3d F2 = Eigen::Isometry3d::Identity();
  F2.translation() = Eigen::Vector3d(0.2, 0.1, 0);
  F2.linear() = Eigen::AngleAxisd(-kPi / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  chain.fixed.push_back(F2);
  chain.fixed.push_back(Eigen::Isometry3d(Eigen::Translation3d(0, 0, 0.1)));
  const auto converted = ChainToMcpc(chain);
  ASSERT_TRUE(converted.ok());
  EXPECT_FALSE(converted->notes.empty());
  ExpectSameKinematics(chain, converted->model, 52);
}

TEST(Chain, McpcToChainAndBackIsTheSameRobot) {
  for (unsigned seed = 60; seed < 64; ++seed) {
    const RobotModel model = testing::RandomModel({R, R, P, R, R, R}, seed);
    const GenericChain chain = McpcToChain(model);
    ExpectSameKinematics(chain, model, seed);
    const auto back = ChainToMcpc(chain);
    ASSERT_TRUE(back.ok());
    ExpectSameKinematics(chain, back->model, seed + 1);
  }
}

TEST(Chain, BadChainsAreErrors) {
  GenericChain chain = RandomChain({R, R}, 70);
  chain.joints[1].axis = Eigen::Vector3d::Zero();
  EXPECT_NE(ChainToMcpc(chain).error().message.find("J2"), std::string::npos);
  chain = RandomChain({R, R}, 70);
  chain.fixed.pop_back();
  EXPECT_FALSE(ChainToMcpc(chain).ok());
  chain = RandomChain({R, R}, 70);
  chain.fixed[1](0, 3) = std::nan("");
  EXPECT_FALSE(ChainToMcpc(chain).ok());
  EXPECT_FALSE(ChainToMcpc(GenericChain{}).ok());
}

TEST(Chain, FullTransformParamsRoundTripIncludingGimbalLock) {
  std::mt19937 rng(80);
  for (int trial = 0; trial < 100; ++trial) {
    Eigen::Isometry3d T = RandomIsometry(rng);
    if (trial % 10 == 0) {  // beta = +-90 deg exactly
      T.linear() =
          Eigen::AngleAxisd(0.3 * trial, Eigen::Vector3d::UnitX()) *
          Eigen::AngleAxisd(trial % 20 == 0 ? kPi / 2 : -kPi / 2, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    }
    const Eigen::Isometry3d back = FromFullTransformParams(ToFullTransformParams(T));
    EXPECT_LT((back.matrix() - T.matrix()).cwiseAbs().maxCoeff(), 1e-14) << trial;
  }
}

// Standard DH, composed independently with 4 x 4 matrices.
Eigen::Matrix4d DhMatrix(double theta, double d, double a, double alpha) {
  const double ct = std::cos(theta), st = std::sin(theta);
  const double ca = std::cos(alpha), sa = std::sin(alpha);
  Eigen::Matrix4d m;
  m << ct, -st * ca, st * sa, a * ct, st, ct * ca, -ct * sa, a * st, 0, sa, ca, d, 0, 0, 0, 1;
  return m;
}

TEST(Chain, DhTablesConvertExactly) {
  std::mt19937 rng(90);
  std::uniform_real_distribution<double> u(-1, 1);
  DhTable table;
  table.name = "dh";
  table.T_base_frame0 = RandomIsometry(rng);
  table.T_framen_tool = RandomIsometry(rng);
  const std::vector<JointType> types = {R, R, P, R, R, R};
  for (std::size_t i = 0; i < types.size(); ++i) {
    table.rows.push_back({Joint(i, types[i]), 0.3 * u(rng), 3 * u(rng), 0.3 * u(rng), 3 * u(rng)});
  }
  table.rows[4].alpha = 0;  // parallel axes 5 and 6
  const auto converted = ChainToMcpc(DhToChain(table));
  ASSERT_TRUE(converted.ok());
  std::uniform_real_distribution<double> unit(0, 1);
  for (int trial = 0; trial < 100; ++trial) {
    Eigen::Matrix4d expected = table.T_base_frame0.matrix();
    std::vector<double> q;
    for (const DhRow& row : table.rows) {
      const double v = row.joint.lower + unit(rng) * (row.joint.upper - row.joint.lower);
      q.push_back(v);
      expected *= row.joint.type == R ? DhMatrix(row.theta + v, row.d, row.a, row.alpha)
                                      : DhMatrix(row.theta, row.d + v, row.a, row.alpha);
    }
    expected *= table.T_framen_tool.matrix();
    const Eigen::Matrix4d actual = ForwardKinematics(converted->model, q).matrix();
    EXPECT_LT((actual - expected).cwiseAbs().maxCoeff(), 1e-12) << "trial " << trial;
  }
}

}  // namespace
}  // namespace selfcal
