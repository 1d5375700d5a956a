// The analytic Jacobian of core/model/jacobian.h (the one the engine uses) against Ceres'
// automatic differentiation of the templated forward kinematics (ceres::Jet), for parameters,
// joints and transformed points, and the engine's point-to-plane derivative built from it against
// numeric differentiation (Ceres' GradientChecker).
#include "core/model/jacobian.h"

#include <ceres/ceres.h>
#include <ceres/gradient_checker.h>
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <random>

#include "core/model/kinematics.h"
#include "tests/core/test_models.h"

namespace selfcal {
namespace {

using testing::RandomModel;

// [omega]_x = dR R^T  ->  omega.
template <typename Derived>
Eigen::Vector3d Vee(const Eigen::MatrixBase<Derived>& S) {
  return {S(2, 1), S(0, 2), S(1, 0)};
}

// The 6 x N Jacobian of T_base_sensor from jets whose N dual parts are the differentiated inputs.
template <int N>
PoseJacobian FromJets(const Transform3<ceres::Jet<double, N>>& T) {
  PoseJacobian J(6, N);
  Eigen::Matrix3d R;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) R(r, c) = T.linear()(r, c).a;
  }
  for (int i = 0; i < N; ++i) {
    Eigen::Matrix3d dR;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) dR(r, c) = T.linear()(r, c).v[i];
    }
    for (int r = 0; r < 3; ++r) J(r, i) = T.translation()(r).v[i];
    J.block<3, 1>(3, i) = Vee(dR * R.transpose());
    // dR R^T must be skew-symmetric for a rotation: checks the jets themselves.
    EXPECT_LT(((dR * R.transpose()) + (dR * R.transpose()).transpose()).cwiseAbs().maxCoeff(),
              1e-12);
  }
  return J;
}

template <int K>
void CheckParameterJacobian(const RobotModel& model, unsigned seed) {
  using Jet = ceres::Jet<double, K>;
  ASSERT_EQ(model.ParameterCount(), static_cast<std::size_t>(K));
  const std::vector<JointType> types = JointTypes(model);
  const std::vector<double> k = ToParameterVector(model);
  std::vector<Jet> k_jet(K);
  for (int i = 0; i < K; ++i)
    k_jet[static_cast<std::size_t>(i)] = Jet(k[static_cast<std::size_t>(i)], i);

  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  std::uniform_real_distribution<double> coordinate(-2, 2);
  for (int trial = 0; trial < 25; ++trial) {
    std::vector<double> q(model.JointCount());
    for (std::size_t i = 0; i < q.size(); ++i) {
      q[i] = model.joints[i].lower + unit(rng) * (model.joints[i].upper - model.joints[i].lower);
    }
    const auto T_jet = ForwardKinematics<Jet, double>(types, k_jet.data(), q.data());
    const PoseJacobian expected = FromJets<K>(T_jet);

    PoseJacobian analytic;
    const Eigen::Isometry3d T = ForwardKinematicsWithJacobian(types, k, q, &analytic);
    const Eigen::Isometry3d T_plain = ForwardKinematics(model, q);
    EXPECT_LT((T.matrix() - T_plain.matrix()).cwiseAbs().maxCoeff(), 1e-12);
    ASSERT_EQ(analytic.cols(), K);
    EXPECT_LT((analytic - expected).cwiseAbs().maxCoeff(), 1e-12)
        << "trial " << trial << "\nanalytic\n"
        << analytic << "\nautomatic\n"
        << expected;

    // A point in the sensor frame, chained through the pose Jacobian.
    const Eigen::Vector3d p_sensor(coordinate(rng), coordinate(rng), coordinate(rng));
    const Eigen::Matrix<Jet, 3, 1> p_jet = T_jet * p_sensor.cast<Jet>();
    PointJacobian point;
    ChainPointJacobian(analytic, T, p_sensor, &point);
    ASSERT_EQ(point.cols(), K);
    for (int r = 0; r < 3; ++r) {
      EXPECT_NEAR(p_jet(r).a, (T * p_sensor)(r), 1e-12);
      for (int i = 0; i < K; ++i) {
        EXPECT_NEAR(point(r, i), p_jet(r).v[i], 1e-12) << "row " << r << " parameter " << i;
      }
    }
  }
}

template <int N>
void CheckJointJacobian(const RobotModel& model, unsigned seed) {
  using Jet = ceres::Jet<double, N>;
  ASSERT_EQ(model.JointCount(), static_cast<std::size_t>(N));
  const std::vector<JointType> types = JointTypes(model);
  const std::vector<double> k = ToParameterVector(model);
  std::vector<Jet> k_jet;
  for (double v : k) k_jet.emplace_back(v);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  for (int trial = 0; trial < 10; ++trial) {
    std::vector<double> q(model.JointCount());
    std::vector<Jet> q_jet;
    for (std::size_t i = 0; i < q.size(); ++i) {
      q[i] = model.joints[i].lower + unit(rng) * (model.joints[i].upper - model.joints[i].lower);
      q_jet.emplace_back(q[i], static_cast<int>(i));
    }
    const auto T_jet = ForwardKinematics<Jet, Jet>(types, k_jet.data(), q_jet.data());
    PoseJacobian joints;
    ForwardKinematicsWithJacobian(types, k, q, nullptr, &joints);
    EXPECT_LT((joints - FromJets<N>(T_jet)).cwiseAbs().maxCoeff(), 1e-12) << "trial " << trial;
  }
}

constexpr auto R = JointType::kRevolute;
constexpr auto P = JointType::kPrismatic;

TEST(Jacobian, SevenRevoluteJointsMatchAutomaticDifferentiation) {
  for (unsigned seed : {1u, 2u, 3u}) {
    CheckParameterJacobian<36>(RandomModel({R, R, R, R, R, R, R}, seed), seed + 100);
  }
}

TEST(Jacobian, MixedRevoluteAndPrismaticMatchAutomaticDifferentiation) {
  for (unsigned seed : {4u, 5u}) {
    CheckParameterJacobian<32>(RandomModel({P, R, P, P, R, R}, seed), seed + 100);
  }
  CheckParameterJacobian<12>(RandomModel({P}, 6), 106);
  CheckParameterJacobian<12>(RandomModel({R}, 7), 107);
}

TEST(Jacobian, JointDerivativesMatchAutomaticDifferentiation) {
  CheckJointJacobian<7>(RandomModel({R, R, R, R, R, R, R}, 8), 108);
  CheckJointJacobian<6>(RandomModel({P, R, P, P, R, R}, 9), 109);
}

TEST(Jacobian, WithoutOutputsItIsPlainForwardKinematics) {
  const RobotModel model = RandomModel({R, P, R}, 10);
  const std::vector<double> q = {0.3, 0.1, -1.2};
  const Eigen::Isometry3d T =
      ForwardKinematicsWithJacobian(JointTypes(model), ToParameterVector(model), q, nullptr);
  EXPECT_LT((T.matrix() - ForwardKinematics(model, q).matrix()).cwiseAbs().maxCoeff(), 1e-14);
}

// c(k) = n . (tr(k, j_i) p_i - tr(k, j_j) p_j), the engine's point-to-plane residual, with the
// derivative the engine builds from the pose Jacobian (core/calib/point_to_plane.cc,
// rigid_pair.cc): dc/dk = (n, (R_i p_i) x n) . J_i - (n, (R_j p_j) x n) . J_j.
class PointToPlane : public ceres::CostFunction {
 public:
  PointToPlane(std::vector<JointType> types, std::vector<double> joints_i,
               std::vector<double> joints_j, Eigen::Vector3d p_i, Eigen::Vector3d p_j,
               Eigen::Vector3d n)
      : types_(std::move(types)),
        joints_i_(std::move(joints_i)),
        joints_j_(std::move(joints_j)),
        p_i_(p_i),
        p_j_(p_j),
        n_(n) {
    set_num_residuals(1);
    mutable_parameter_block_sizes()->push_back(static_cast<int>(ParameterCountOf(types_.size())));
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const std::span<const double> k(parameters[0], ParameterCountOf(types_.size()));
    PoseJacobian J_i, J_j;
    const Eigen::Isometry3d T_i = ForwardKinematicsWithJacobian(types_, k, joints_i_, &J_i);
    const Eigen::Isometry3d T_j = ForwardKinematicsWithJacobian(types_, k, joints_j_, &J_j);
    const Eigen::Vector3d r_i = T_i.linear() * p_i_, r_j = T_j.linear() * p_j_;
    residuals[0] = n_.dot(r_i + T_i.translation() - r_j - T_j.translation());
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::Matrix<double, 6, 1> a, b;
      a << n_, r_i.cross(n_);
      b << n_, r_j.cross(n_);
      const Eigen::VectorXd row = J_i.transpose() * a - J_j.transpose() * b;
      for (long c = 0; c < row.size(); ++c) jacobians[0][c] = row[c];
    }
    return true;
  }

 private:
  std::vector<JointType> types_;
  std::vector<double> joints_i_, joints_j_;
  Eigen::Vector3d p_i_, p_j_, n_;
};

TEST(Jacobian, PointToPlaneDerivativePassesCeresGradientChecker) {
  const RobotModel model = RandomModel({R, R, R, R, R, R, R}, 21);
  std::vector<double> k = ToParameterVector(model);
  std::mt19937 rng(22);
  std::uniform_real_distribution<double> unit(0, 1);
  for (int trial = 0; trial < 3; ++trial) {
    std::vector<double> q_i(model.JointCount()), q_j(model.JointCount());
    for (std::size_t i = 0; i < q_i.size(); ++i) {
      const JointSpec& joint = model.joints[i];
      q_i[i] = joint.lower + unit(rng) * (joint.upper - joint.lower);
      q_j[i] = joint.lower + unit(rng) * (joint.upper - joint.lower);
    }
    PointToPlane cost(JointTypes(model), q_i, q_j, {0.1, -0.3, 1.4}, {-0.2, 0.1, 1.1},
                      Eigen::Vector3d(0.3, -0.5, 0.8).normalized());
    ceres::NumericDiffOptions numeric;
    const std::vector<const ceres::Manifold*>* no_manifolds = nullptr;
    ceres::GradientChecker checker(&cost, no_manifolds, numeric);
    ceres::GradientChecker::ProbeResults results;
    const double* parameters[] = {k.data()};
    EXPECT_TRUE(checker.Probe(parameters, 1e-7, &results)) << results.error_log;
  }
}

}  // namespace
}  // namespace selfcal
