#include "core/calib/reference_solver.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace selfcal::calib {

namespace {

constexpr int kSevenJointParameters = 12 + 4 * 6;

// c = [tr(k, j_i) p_i - tr(k, j_j) p_j] . n, through the full chain (core/model/kinematics.h).
struct PointToPlaneResidual {
  const Chain* chain;
  std::array<double, kMaxJoints> joints_i{}, joints_j{};  // normalized (prismatic / s)
  Eigen::Vector3d p_i, p_j, n;  // n: the match's normal times sqrt(weight) (robust_loss.h)

  // Fixed-size entry (AutoDiffCostFunction) for the common 7-joint arm.
  template <typename T>
  bool operator()(const T* k, T* residual) const {
    return Evaluate(k, residual);
  }
  // Dynamic entry (DynamicAutoDiffCostFunction) for any other chain.
  template <typename T>
  bool operator()(T const* const* parameters, T* residual) const {
    return Evaluate(parameters[0], residual);
  }
  template <typename T>
  bool Evaluate(const T* k, T* residual) const {
    const Transform3<T> T_i = ForwardKinematics<T, double>(chain->joint_types, k, joints_i.data());
    const Transform3<T> T_j = ForwardKinematics<T, double>(chain->joint_types, k, joints_j.data());
    const Eigen::Matrix<T, 3, 1> difference = T_i * p_i.cast<T>() - T_j * p_j.cast<T>();
    residual[0] = difference.dot(n.cast<T>());
    return true;
  }
};

}  // namespace

bool SolveReference(const std::vector<Dataset>& datasets, const Chain& chain,
                    const MatchProblem& problem, int max_iterations, int threads,
                    std::vector<double>& k_hat, LmSummary& summary) {
  const int parameter_count = static_cast<int>(k_hat.size());
  ceres::Problem::Options problem_options;
  problem_options.enable_fast_removal = false;
  ceres::Problem ceres_problem(problem_options);
  std::vector<int> constant;
  std::vector<bool> is_free(k_hat.size(), false);
  for (std::size_t index : problem.free()) is_free[index] = true;
  for (int i = 0; i < parameter_count; ++i) {
    if (!is_free[static_cast<std::size_t>(i)]) constant.push_back(i);
  }
  ceres_problem.AddParameterBlock(
      k_hat.data(), parameter_count,
      constant.empty() ? nullptr : new ceres::SubsetManifold(parameter_count, constant));
  const std::size_t joint_count = chain.JointCount();
  for (const FrozenMatch& match : problem.matches()) {
    auto* functor = new PointToPlaneResidual;
    functor->chain = &chain;
    const Dataset& dataset_i = datasets[match.dataset_i];
    const Dataset& dataset_j = datasets[match.dataset_j];
    double raw[kMaxJoints], buffer[kMaxJoints];
    const double* joints_i = chain.NormalizedJoints(
        dataset_i.JointsOfPose(dataset_i.PoseOf(match.point_i), raw), buffer);
    std::copy_n(joints_i, joint_count, functor->joints_i.begin());
    const double* joints_j = chain.NormalizedJoints(
        dataset_j.JointsOfPose(dataset_j.PoseOf(match.point_j), raw), buffer);
    std::copy_n(joints_j, joint_count, functor->joints_j.begin());
    functor->p_i = NormalizedSensorPoint(dataset_i, match.point_i, chain.scale);
    functor->p_j = NormalizedSensorPoint(dataset_j, match.point_j, chain.scale);
    functor->n = std::sqrt(static_cast<double>(match.weight)) *
                 Eigen::Vector3d(match.nx, match.ny, match.nz);
    if (parameter_count == kSevenJointParameters) {
      ceres_problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<PointToPlaneResidual, 1, kSevenJointParameters>(functor),
          nullptr, k_hat.data());
    } else {
      auto* cost = new ceres::DynamicAutoDiffCostFunction<PointToPlaneResidual, 8>(functor);
      cost->AddParameterBlock(parameter_count);
      cost->SetNumResiduals(1);
      ceres_problem.AddResidualBlock(cost, nullptr, k_hat.data());
    }
  }
  ceres::Solver::Options options;
  options.minimizer_type = ceres::TRUST_REGION;
  options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  options.max_num_iterations = max_iterations;
  options.num_threads = std::max(1, threads);
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  ceres::Solver::Summary ceres_summary;
  ceres::Solve(options, &ceres_problem, &ceres_summary);
  summary.iterations = static_cast<int>(ceres_summary.iterations.size());
  summary.initial_cost = ceres_summary.initial_cost;
  summary.final_cost = ceres_summary.final_cost;
  return ceres_summary.IsSolutionUsable() && std::isfinite(ceres_summary.final_cost);
}

}  // namespace selfcal::calib
