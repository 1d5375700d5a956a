#include "core/calib/point_to_plane.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "core/calib/parallel.h"

namespace selfcal::calib {

namespace {

constexpr std::size_t kChunkSize = 8192;

struct PosesOfDataset {
  std::vector<Eigen::Matrix<double, 3, 4>> transforms;
  std::vector<Eigen::Matrix<double, 6, Eigen::Dynamic>> jacobians;  // free columns only
};

Eigen::Matrix<double, 6, Eigen::Dynamic> FreeColumns(const PoseJacobian& full, const std::vector<std::size_t>& free) {
  Eigen::Matrix<double, 6, Eigen::Dynamic> result(6, static_cast<long>(free.size()));
  for (std::size_t c = 0; c < free.size(); ++c) result.col(static_cast<long>(c)) = full.col(static_cast<long>(free[c]));
  return result;
}

}  // namespace

MatchProblem::MatchProblem(const std::vector<Dataset>& datasets, const Chain& chain, std::vector<std::size_t> free,
                           int threads)
    : datasets_(datasets), chain_(chain), free_(std::move(free)), threads_(threads) {}

void MatchProblem::SetMatches(const std::vector<PairMatches>& matches, const std::vector<ProjectedCloud>& clouds) {
  matches_.clear();
  chunks_.clear();
  for (const PairMatches& pair : matches) {
    const ProjectedCloud& cloud_i = clouds[pair.dataset_i];
    const bool single = datasets_[pair.dataset_i].layout == PoseLayout::kOnePerScan &&
                        datasets_[pair.dataset_j].layout == PoseLayout::kOnePerScan;
    const std::size_t first = matches_.size();
    for (std::size_t k = 0; k < pair.size(); ++k) {
      const std::uint32_t u = pair.point_i[k];
      matches_.push_back({pair.dataset_i, u, pair.dataset_j, pair.point_j[k], cloud_i.nx[u], cloud_i.ny[u],
                          cloud_i.nz[u]});
    }
    // Chunks never cross pairs, so a single-pose pair's chunk shares both poses.
    for (std::size_t begin = first; begin < matches_.size(); begin += kChunkSize) {
      chunks_.push_back({begin, std::min(matches_.size(), begin + kChunkSize), single});
    }
  }
}

NormalEquations MatchProblem::Evaluate(const std::vector<double>& k_hat, bool linearize) const {
  const long K = static_cast<long>(free_.size());
  // Poses (and Jacobians) of every dataset that has a pose per scan or per column.
  std::vector<PosesOfDataset> poses(datasets_.size());
  ParallelFor(datasets_.size(), threads_, [&](std::size_t d) {
    const Dataset& dataset = datasets_[d];
    if (dataset.layout == PoseLayout::kOnePerPoint) return;
    PosesOfDataset& out = poses[d];
    out.transforms.resize(dataset.PoseCount());
    if (linearize) out.jacobians.resize(dataset.PoseCount());
    PoseJacobian full;
    for (std::size_t pose = 0; pose < dataset.PoseCount(); ++pose) {
      Transform3<double> T;
      if (linearize) {
        chain_.PoseWithJacobian(k_hat.data(), dataset.JointsOfPose(pose), T, full);
        out.jacobians[pose] = FreeColumns(full, free_);
      } else {
        T = chain_.Pose(k_hat.data(), dataset.JointsOfPose(pose));
      }
      out.transforms[pose] = T.matrix().topRows<3>();
    }
  });

  std::vector<NormalEquations> partial(chunks_.size());
  ParallelFor(chunks_.size(), threads_, [&](std::size_t c) {
    const Chunk& chunk = chunks_[c];
    NormalEquations& out = partial[c];
    if (linearize) {
      out.hessian = Eigen::MatrixXd::Zero(K, K);
      out.gradient = Eigen::VectorXd::Zero(K);
    }
    Eigen::Matrix<double, 12, 12> block = Eigen::Matrix<double, 12, 12>::Zero();
    Eigen::Matrix<double, 12, 1> block_gradient = Eigen::Matrix<double, 12, 1>::Zero();
    Eigen::Matrix<double, 6, Eigen::Dynamic> local_i(6, K), local_j(6, K);
    PoseJacobian full;
    Eigen::VectorXd row(K);
    // Resolves the pose of one end of a match: stored, or computed here for per-point poses.
    auto pose_of = [&](std::uint32_t d, std::uint32_t point, Eigen::Matrix<double, 3, 4>& T,
                       Eigen::Matrix<double, 6, Eigen::Dynamic>& local) -> const Eigen::Matrix<double, 6, Eigen::Dynamic>* {
      const Dataset& dataset = datasets_[d];
      const std::size_t pose = dataset.PoseOf(point);
      if (dataset.layout != PoseLayout::kOnePerPoint) {
        T = poses[d].transforms[pose];
        return linearize ? &poses[d].jacobians[pose] : nullptr;
      }
      Transform3<double> transform;
      if (linearize) {
        chain_.PoseWithJacobian(k_hat.data(), dataset.JointsOfPose(pose), transform, full);
        local = FreeColumns(full, free_);
      } else {
        transform = chain_.Pose(k_hat.data(), dataset.JointsOfPose(pose));
      }
      T = transform.matrix().topRows<3>();
      return linearize ? &local : nullptr;
    };
    const Eigen::Matrix<double, 6, Eigen::Dynamic>* jacobian_i = nullptr;
    const Eigen::Matrix<double, 6, Eigen::Dynamic>* jacobian_j = nullptr;
    for (std::size_t m = chunk.begin; m < chunk.end; ++m) {
      const FrozenMatch& match = matches_[m];
      Eigen::Matrix<double, 3, 4> T_i, T_j;
      jacobian_i = pose_of(match.dataset_i, match.point_i, T_i, local_i);
      jacobian_j = pose_of(match.dataset_j, match.point_j, T_j, local_j);
      const Eigen::Vector3d p_i = NormalizedSensorPoint(datasets_[match.dataset_i], match.point_i, chain_.scale);
      const Eigen::Vector3d p_j = NormalizedSensorPoint(datasets_[match.dataset_j], match.point_j, chain_.scale);
      const Eigen::Vector3d q_i = T_i.leftCols<3>() * p_i + T_i.col(3);
      const Eigen::Vector3d q_j = T_j.leftCols<3>() * p_j + T_j.col(3);
      const Eigen::Vector3d n(match.nx, match.ny, match.nz);
      const double r = n.dot(q_i - q_j);
      out.cost += 0.5 * r * r;
      ++out.residuals;
      if (!linearize) continue;
      Eigen::Matrix<double, 12, 1> c;
      c << n, q_i.cross(n), n, q_j.cross(n);
      if (chunk.single_pose_pair) {
        block.selfadjointView<Eigen::Lower>().rankUpdate(c);
        block_gradient += c * r;
      } else {
        row.noalias() = jacobian_i->transpose() * c.head<6>() - jacobian_j->transpose() * c.tail<6>();
        out.hessian.selfadjointView<Eigen::Lower>().rankUpdate(row);
        out.gradient += row * r;
      }
    }
    if (linearize && chunk.single_pose_pair && chunk.end > chunk.begin) {
      Eigen::Matrix<double, 12, Eigen::Dynamic> stacked(12, K);
      stacked.topRows<6>() = *jacobian_i;
      stacked.bottomRows<6>() = -*jacobian_j;
      const Eigen::Matrix<double, 12, 12> full_block = block.selfadjointView<Eigen::Lower>();
      out.hessian.noalias() += stacked.transpose() * full_block * stacked;
      out.gradient.noalias() += stacked.transpose() * block_gradient;
    } else if (linearize) {
      const Eigen::MatrixXd symmetric = out.hessian.selfadjointView<Eigen::Lower>();
      out.hessian = symmetric;
    }
  });
  NormalEquations total;
  if (linearize) {
    total.hessian = Eigen::MatrixXd::Zero(K, K);
    total.gradient = Eigen::VectorXd::Zero(K);
  }
  for (const NormalEquations& part : partial) {  // in chunk order: deterministic
    total.cost += part.cost;
    total.residuals += part.residuals;
    if (linearize) {
      total.hessian += part.hessian;
      total.gradient += part.gradient;
    }
  }
  return total;
}

bool SolveLevenbergMarquardt(const MatchProblem& problem, int max_iterations, std::vector<double>& k_hat,
                             LmSummary& summary, const std::atomic<bool>* cancel) {
  const auto& free = problem.free();
  const long K = static_cast<long>(free.size());
  NormalEquations current = problem.Evaluate(k_hat, true);
  summary.initial_cost = summary.final_cost = current.cost;
  if (!std::isfinite(current.cost)) return false;
  double radius = 1e4;  // Ceres' initial trust region radius; lambda = 1 / radius
  double decrease_factor = 2.0;
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    if (cancel != nullptr && cancel->load()) break;
    if (current.gradient.lpNorm<Eigen::Infinity>() <= 1e-10) break;
    Eigen::VectorXd diagonal = current.hessian.diagonal().cwiseMax(1e-6).cwiseMin(1e32);
    Eigen::MatrixXd damped = current.hessian;
    damped.diagonal() += diagonal / radius;
    const Eigen::VectorXd step = damped.ldlt().solve(-current.gradient);
    if (!step.allFinite()) return false;
    Eigen::VectorXd x(K);
    for (long c = 0; c < K; ++c) x[c] = k_hat[free[static_cast<std::size_t>(c)]];
    summary.iterations = iteration + 1;
    if (step.norm() <= 1e-8 * (x.norm() + 1e-8)) break;
    std::vector<double> candidate = k_hat;
    for (long c = 0; c < K; ++c) candidate[free[static_cast<std::size_t>(c)]] += step[c];
    const double candidate_cost = problem.Evaluate(candidate, false).cost;
    const double model_decrease = -(current.gradient.dot(step) + 0.5 * step.dot(current.hessian * step));
    const double actual_decrease = current.cost - candidate_cost;
    const double rho = model_decrease > 0 ? actual_decrease / model_decrease : -1.0;
    if (std::isfinite(candidate_cost) && rho > 1e-3) {
      k_hat = candidate;
      const double relative = actual_decrease / std::max(current.cost, 1e-300);
      radius = radius / std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
      decrease_factor = 2.0;
      current = problem.Evaluate(k_hat, true);
      summary.final_cost = current.cost;
      if (relative <= 1e-6) break;
    } else {
      radius /= decrease_factor;
      decrease_factor *= 2.0;
      if (radius < 1e-32) break;
    }
  }
  return std::isfinite(summary.final_cost);
}

}  // namespace selfcal::calib
