// The per-pose 6 x K Jacobian (pose_jacobian.h) and the fast point-to-plane derivative built from
// it, checked with Ceres' GradientChecker (numeric differentiation) and against automatic
// differentiation of core/model's templated ForwardKinematics.
#include <ceres/ceres.h>
#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include "core/calib/pose_jacobian.h"
#include "tests/calib/synthetic.h"

namespace selfcal::calib {
namespace {

// c(k) = [tr(k, j_i) p_i - tr(k, j_j) p_j] . n with the analytic derivative of the fast mode:
// dc/dk = (n, q_i x n) . J_i - (n, q_j x n) . J_j.
class FastPointToPlane : public ceres::CostFunction {
 public:
  FastPointToPlane(std::vector<JointType> types, std::vector<double> joints_i,
                   std::vector<double> joints_j, Eigen::Vector3d p_i, Eigen::Vector3d p_j,
                   Eigen::Vector3d n)
      : types_(std::move(types)),
        joints_i_(std::move(joints_i)),
        joints_j_(std::move(joints_j)),
        p_i_(p_i),
        p_j_(p_j),
        n_(n) {
    set_num_residuals(1);
    mutable_parameter_block_sizes()->push_back(static_cast<int>(12 + 4 * (types_.size() - 1)));
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    Transform3<double> T_i, T_j;
    PoseJacobian J_i, J_j;
    ForwardKinematicsWithJacobian(types_, parameters[0], joints_i_.data(), T_i, J_i);
    ForwardKinematicsWithJacobian(types_, parameters[0], joints_j_.data(), T_j, J_j);
    const Eigen::Vector3d q_i = T_i * p_i_, q_j = T_j * p_j_;
    residuals[0] = n_.dot(q_i - q_j);
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::Matrix<double, 6, 1> a, b;
      a << n_, q_i.cross(n_);
      b << n_, q_j.cross(n_);
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

TEST(PoseJacobian, PointToPlaneDerivativePassesCeresGradientChecker) {
  const RobotModel robot = testing::LoadIiwa();
  std::vector<double> k = ToParameterVector(testing::PerturbedModel(robot, 5, 0.01, 0.05));
  const auto configurations = testing::WorkspaceConfigurations(6, 21);
  for (std::size_t c = 0; c + 1 < configurations.size(); c += 2) {
    FastPointToPlane cost(JointTypes(robot), configurations[c], configurations[c + 1],
                          {0.1, -0.3, 1.4}, {-0.2, 0.1, 1.1},
                          Eigen::Vector3d(0.3, -0.5, 0.8).normalized());
    ceres::NumericDiffOptions numeric;
    const std::vector<const ceres::Manifold*>* no_manifolds = nullptr;
    ceres::GradientChecker checker(&cost, no_manifolds, numeric);
    ceres::GradientChecker::ProbeResults results;
    const double* parameters[] = {k.data()};
    EXPECT_TRUE(checker.Probe(parameters, 1e-7, &results)) << results.error_log;
  }
}

TEST(PoseJacobian, EqualsAutomaticDifferentiationOfTheChain) {
  const RobotModel robot = testing::LoadIiwa();
  const std::vector<JointType> types = JointTypes(robot);
  const std::vector<double> k = ToParameterVector(testing::PerturbedModel(robot, 9, 0.01, 0.05));
  const std::vector<double> joints = {0.3, -0.4, 1.1, -1.3, 0.2, 0.9, -2.0};
  const Eigen::Vector3d p(0.3, 0.2, 1.7);
  Transform3<double> T;
  PoseJacobian J;
  ForwardKinematicsWithJacobian(types, k.data(), joints.data(), T, J);
  EXPECT_TRUE(T.isApprox(ForwardKinematics<double, double>(types, k.data(), joints.data()), 1e-12));
  // Each parameter on its own through a one-dimensional jet.
  using Jet = ceres::Jet<double, 1>;
  for (std::size_t l = 0; l < k.size(); ++l) {
    std::vector<Jet> k_jet(k.begin(), k.end());
    k_jet[l].v[0] = 1.0;
    const Transform3<Jet> T_jet =
        ForwardKinematics<Jet, double>(types, k_jet.data(), joints.data());
    const Eigen::Matrix<Jet, 3, 1> q = T_jet * p.cast<Jet>();
    const Eigen::Vector3d expected(q.x().v[0], q.y().v[0], q.z().v[0]);
    const Eigen::Vector3d twist_derivative =
        J.col(static_cast<long>(l)).tail<3>().cross(T * p) + J.col(static_cast<long>(l)).head<3>();
    EXPECT_TRUE(twist_derivative.isApprox(expected, 1e-10) ||
                (twist_derivative - expected).norm() < 1e-12)
        << ParameterName(robot, l) << ": " << twist_derivative.transpose() << " vs "
        << expected.transpose();
  }
}

}  // namespace
}  // namespace selfcal::calib
