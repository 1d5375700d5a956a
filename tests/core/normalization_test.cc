// The paper's normalization by s: parameters and prismatic joints scale, FK scales with them.
#include "core/model/normalization.h"

#include <gtest/gtest.h>

#include <random>

#include "core/model/jacobian.h"
#include "core/model/kinematics.h"
#include "tests/core/test_models.h"

namespace selfcal {
namespace {

constexpr auto R = JointType::kRevolute;
constexpr auto P = JointType::kPrismatic;

TEST(Normalization, TranslationIndicesAgreeWithTheModelsOwnAnswer) {
  const RobotModel model = testing::RandomModel({R, P, R, R}, 1);
  std::size_t translations = 0;
  for (std::size_t i = 0; i < model.ParameterCount(); ++i) {
    EXPECT_EQ(IsTranslationIndex(i, model.JointCount()), IsTranslationParameter(model, i)) << i;
    translations += IsTranslationIndex(i, 4) ? 1 : 0;
  }
  EXPECT_EQ(translations, 3u + 2u * 3u + 3u);
}

TEST(Normalization, ScalesExactlyTheTranslationsAndRoundTrips) {
  const RobotModel model = testing::RandomModel({R, P, R, R}, 2);
  const std::vector<double> k = ToParameterVector(model);
  std::vector<double> k_hat = k;
  const double s = 1.7;
  NormalizeTranslationParameters(k_hat, model.JointCount(), s);
  for (std::size_t i = 0; i < k.size(); ++i) {
    if (IsTranslationParameter(model, i)) {
      EXPECT_DOUBLE_EQ(k_hat[i], k[i] / s) << ParameterName(model, i);
    } else {
      EXPECT_EQ(k_hat[i], k[i]) << ParameterName(model, i);
    }
  }
  // The paper's order: tool gamma is an angle, tool z a translation.
  EXPECT_EQ(k_hat[ToolOffset(4) + 2], k[ToolOffset(4) + 2]);
  EXPECT_DOUBLE_EQ(k_hat[ToolOffset(4) + 5], k[ToolOffset(4) + 5] / s);
  DenormalizeTranslationParameters(k_hat, model.JointCount(), s);
  for (std::size_t i = 0; i < k.size(); ++i) EXPECT_NEAR(k_hat[i], k[i], 1e-15);
}

TEST(Normalization, ForwardKinematicsOfNormalizedInputsIsScaledByS) {
  const RobotModel model = testing::RandomModel({P, R, P, R, R}, 3);
  const std::vector<JointType> types = JointTypes(model);
  std::vector<double> k_hat = ToParameterVector(model);
  const double s = 2.37;
  NormalizeTranslationParameters(k_hat, model.JointCount(), s);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> q = {0.2 * u(rng), 2 * u(rng), 0.3 * u(rng), 2 * u(rng), 2 * u(rng)};
    const Eigen::Isometry3d T = ForwardKinematics(model, q);
    std::vector<double> q_hat = q;
    NormalizeJointPositions(q_hat, types, s);
    EXPECT_EQ(q_hat[1], q[1]);
    EXPECT_DOUBLE_EQ(q_hat[0], q[0] / s);
    const auto T_hat = ForwardKinematics<double, double>(types, k_hat.data(), q_hat.data());
    EXPECT_LT((T_hat.linear() - T.linear()).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((T_hat.translation() * s - T.translation()).norm(), 1e-12);
    // A point: tr(k^, j^) * (p / s) = tr(k, j) * p / s.
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    EXPECT_LT((T_hat * (p / s) - (T * p) / s).norm(), 1e-12);
    DenormalizeJointPositions(q_hat, types, s);
    for (std::size_t i = 0; i < q.size(); ++i) EXPECT_NEAR(q_hat[i], q[i], 1e-15);
  }
}

TEST(Normalization, JacobianOfTheNormalizedChainIsTheScaledJacobian) {
  const RobotModel model = testing::RandomModel({R, P, R, R, P}, 5);
  const std::vector<JointType> types = JointTypes(model);
  const double s = 1.9;
  std::vector<double> k = ToParameterVector(model);
  std::vector<double> k_hat = k;
  NormalizeTranslationParameters(k_hat, model.JointCount(), s);
  std::vector<double> q = {0.4, 0.1, -0.8, 1.2, -0.05};
  std::vector<double> q_hat = q;
  NormalizeJointPositions(q_hat, types, s);
  PoseJacobian J, J_hat;
  ForwardKinematicsWithJacobian(types, k, q, &J);
  ForwardKinematicsWithJacobian(types, k_hat, q_hat, &J_hat);
  for (std::size_t i = 0; i < k.size(); ++i) {
    const auto c = static_cast<Eigen::Index>(i);
    const double row_scale = IsTranslationIndex(i, model.JointCount()) ? 1.0 : 1.0 / s;
    EXPECT_LT((J_hat.block<3, 1>(0, c) - row_scale * J.block<3, 1>(0, c)).norm(), 1e-12) << i;
    EXPECT_LT((J_hat.block<3, 1>(3, c) - J.block<3, 1>(3, c)).norm(), 1e-12) << i;
  }
}

TEST(Normalization, ScaleIsTheMeanDistanceFromTheBase) {
  const std::vector<Eigen::Vector3d> points = {
      {3, 4, 0}, {0, 0, 1}, {std::nan(""), 0, 0}, {0, -2, 0}};
  EXPECT_DOUBLE_EQ(NormalizationScale(points), (5.0 + 1.0 + 2.0) / 3.0);
  EXPECT_EQ(NormalizationScale({}), 0.0);
}

TEST(NormalizationDeathTest, RejectsANonPositiveScale) {
  std::vector<double> k(12, 1.0);
  EXPECT_DEATH(NormalizeTranslationParameters(k, 1, 0.0), "positive");
}

}  // namespace
}  // namespace selfcal
