#include "core/calib/point_to_plane.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "core/calib/parallel.h"

namespace selfcal::calib {

namespace {

constexpr std::size_t kChunkSize = 8192;

using TwistJacobian = Eigen::Matrix<double, 6, Eigen::Dynamic>;
// Transposed (K x 6, column-major): J^T w is six contiguous K-long multiply-adds.
using TwistJacobianTransposed = Eigen::Matrix<double, Eigen::Dynamic, 6>;

TwistJacobian FreeColumns(const PoseJacobian& full, const std::vector<std::size_t>& free) {
  TwistJacobian result(6, static_cast<long>(free.size()));
  for (std::size_t c = 0; c < free.size(); ++c)
    result.col(static_cast<long>(c)) = full.col(static_cast<long>(free[c]));
  return result;
}

bool IsRigid(const Dataset& dataset) { return dataset.layout == PoseLayout::kOnePerScan; }

}  // namespace

MatchProblem::MatchProblem(const std::vector<Dataset>& datasets, const Chain& chain,
                           const std::vector<PoseKnots>& knots, std::vector<std::size_t> free,
                           int threads, bool keep_all_matches)
    : datasets_(datasets),
      chain_(chain),
      knots_(knots),
      free_(std::move(free)),
      threads_(threads),
      keep_all_matches_(keep_all_matches) {
  std::size_t total = 0;
  for (const PoseKnots& dataset_knots : knots_) {
    first_knot_.push_back(total);
    total += dataset_knots.KnotCount();
  }
  first_knot_.push_back(total);
}

void MatchProblem::SetMatches(const std::vector<std::pair<std::uint32_t, std::uint32_t>>& pairs,
                              const std::function<PairMatches(std::size_t)>& match_pair,
                              const std::vector<ProjectedCloud>& clouds,
                              const std::vector<double>& k_hat) {
  Clear();
  std::vector<Eigen::Matrix<double, 3, 4>> rigid_pose(datasets_.size());
  for (std::size_t d = 0; d < datasets_.size(); ++d) {
    if (IsRigid(datasets_[d]))
      rigid_pose[d] = chain_.Pose(k_hat.data(), datasets_[d].JointsOfPose(0)).matrix().topRows<3>();
  }
  // Rigid pairs are reduced as soon as they are matched, so their matches never pile up.
  std::vector<RigidPairCost> reduced(pairs.size());
  std::vector<PairMatches> kept(pairs.size());
  ParallelFor(pairs.size(), threads_, [&](std::size_t p) {
    PairMatches matches = match_pair(p);
    const auto [i, j] = pairs[p];
    if (IsRigid(datasets_[i]) && IsRigid(datasets_[j])) {
      reduced[p] = ReduceRigidPair(matches, clouds[i], datasets_[i], datasets_[j], chain_.scale,
                                   rigid_pose[i], rigid_pose[j]);
      if (!keep_all_matches_) return;
    }
    kept[p] = std::move(matches);
  });
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    const auto [i, j] = pairs[p];
    const bool rigid = IsRigid(datasets_[i]) && IsRigid(datasets_[j]);
    const std::size_t count = rigid ? reduced[p].matches : kept[p].size();
    match_count_ += count;
    per_dataset_[i] += count;
    per_dataset_[j] += count;
    const PairMatches& pair = kept[p];
    const ProjectedCloud& cloud_i = clouds[i];
    if (keep_all_matches_) {  // the reference solver's residuals
      for (std::size_t k = 0; k < pair.size(); ++k) {
        const std::uint32_t u = pair.point_i[k];
        matches_.push_back({i, u, j, pair.point_j[k], cloud_i.nx[u], cloud_i.ny[u], cloud_i.nz[u]});
      }
    }
    if (rigid) {
      if (reduced[p].matches > 0) rigid_pairs_.push_back(std::move(reduced[p]));
      continue;
    }
    // Chunks never cross pairs and depend only on the matches: deterministic sums.
    const Dataset& dataset_i = datasets_[i];
    const Dataset& dataset_j = datasets_[j];
    const std::size_t first = moving_.size();
    for (std::size_t k = 0; k < pair.size(); ++k) {
      const std::uint32_t u = pair.point_i[k], v = pair.point_j[k];
      const std::size_t pose_i = dataset_i.PoseOf(u), pose_j = dataset_j.PoseOf(v);
      MovingMatch match;
      match.p_i[0] = dataset_i.x[u], match.p_i[1] = dataset_i.y[u], match.p_i[2] = dataset_i.z[u];
      match.p_j[0] = dataset_j.x[v], match.p_j[1] = dataset_j.y[v], match.p_j[2] = dataset_j.z[v];
      match.n[0] = cloud_i.nx[u], match.n[1] = cloud_i.ny[u], match.n[2] = cloud_i.nz[u];
      match.alpha_i = knots_[i].alpha[pose_i];
      match.alpha_j = knots_[j].alpha[pose_j];
      match.knot_i = static_cast<std::uint32_t>(first_knot_[i] + knots_[i].segment[pose_i]);
      match.knot_j = static_cast<std::uint32_t>(first_knot_[j] + knots_[j].segment[pose_j]);
      moving_.push_back(match);
    }
    for (std::size_t begin = first; begin < moving_.size(); begin += kChunkSize) {
      chunks_.push_back({begin, std::min(moving_.size(), begin + kChunkSize)});
    }
    kept[p] = PairMatches{};
  }
}

void MatchProblem::Clear() {
  rigid_pairs_ = {};
  moving_ = {};
  matches_ = {};
  chunks_ = {};
  match_count_ = 0;
  per_dataset_.assign(datasets_.size(), 0);
}

NormalEquations MatchProblem::Evaluate(const std::vector<double>& k_hat, bool linearize) const {
  const long K = static_cast<long>(free_.size());
  // Every knot's transform (and Jacobian): one walk along the chain per knot, not per point.
  std::vector<Eigen::Matrix<double, 3, 4>> transforms(first_knot_.back());
  std::vector<TwistJacobianTransposed> jacobians(linearize ? first_knot_.back() : 0);
  ParallelFor(datasets_.size(), threads_, [&](std::size_t d) {
    PoseJacobian full;
    for (std::size_t knot = 0; knot < knots_[d].KnotCount(); ++knot) {
      const double* joints = datasets_[d].JointsOfPose(knots_[d].knot_pose[knot]);
      const std::size_t index = first_knot_[d] + knot;
      Transform3<double> T;
      if (linearize) {
        chain_.PoseWithJacobian(k_hat.data(), joints, T, full);
        jacobians[index] = FreeColumns(full, free_).transpose();
      } else {
        T = chain_.Pose(k_hat.data(), joints);
      }
      transforms[index] = T.matrix().topRows<3>();
    }
  });

  // Rigid pairs: their quadratic forms.
  std::vector<PoseEntriesJacobian> entries_jacobian(linearize ? datasets_.size() : 0);
  if (linearize) {
    for (std::size_t d = 0; d < datasets_.size(); ++d) {
      const std::size_t index = first_knot_[d];
      if (IsRigid(datasets_[d]))
        entries_jacobian[d] =
            PoseEntriesDerivative(transforms[index], jacobians[index].transpose());
    }
  }
  std::vector<NormalEquations> rigid(rigid_pairs_.size());
  ParallelFor(rigid_pairs_.size(), threads_, [&](std::size_t p) {
    const RigidPairCost& pair = rigid_pairs_[p];
    NormalEquations& out = rigid[p];
    if (linearize) {
      out.hessian = Eigen::MatrixXd::Zero(K, K);
      out.gradient = Eigen::VectorXd::Zero(K);
    }
    const Eigen::Matrix<double, 3, 4>& T_i = transforms[first_knot_[pair.dataset_i]];
    const Eigen::Matrix<double, 3, 4>& T_j = transforms[first_knot_[pair.dataset_j]];
    out.cost = 0.5 * RigidPairSquaredSum(pair, Eigen::Map<const PoseEntries>(T_i.data()),
                                         Eigen::Map<const PoseEntries>(T_j.data()),
                                         linearize ? &entries_jacobian[pair.dataset_i] : nullptr,
                                         linearize ? &entries_jacobian[pair.dataset_j] : nullptr,
                                         &out.hessian, &out.gradient);
    out.residuals = pair.matches;
  });

  // Matches of moving scans, one by one through their knots.
  const double inverse_scale = 1.0 / chain_.scale;
  std::vector<NormalEquations> partial(chunks_.size());
  ParallelFor(chunks_.size(), threads_, [&](std::size_t c) {
    const Chunk& chunk = chunks_[c];
    NormalEquations& out = partial[c];
    const long count = static_cast<long>(chunk.end - chunk.begin);
    Eigen::MatrixXd rows;
    Eigen::VectorXd residuals;
    if (linearize) {
      rows.resize(count, K);
      residuals.resize(count);
    }
    Eigen::VectorXd row(K);
    // One end of a match: q = (1 - alpha) T_a p + alpha T_b p; adds sign * d(n . q)/dk to `row`.
    auto end_of = [&](const float* point, std::uint32_t a, double alpha, const Eigen::Vector3d& n,
                      double sign) {
      const Eigen::Vector3d p = Eigen::Vector3d(point[0], point[1], point[2]) * inverse_scale;
      // q through one knot, whose twist Jacobian enters the row with `weight`.
      auto through = [&](std::uint32_t knot, double weight) {
        const Eigen::Vector3d q = transforms[knot].leftCols<3>() * p + transforms[knot].col(3);
        if (linearize) {
          Eigen::Matrix<double, 6, 1> w;
          w << sign * weight * n, sign * weight * q.cross(n);
          row.noalias() += jacobians[knot] * w;
        }
        return q;
      };
      const Eigen::Vector3d q_a = through(a, 1.0 - alpha);
      if (alpha == 0.0) return q_a;
      return Eigen::Vector3d((1.0 - alpha) * q_a + alpha * through(a + 1, alpha));
    };
    for (std::size_t m = chunk.begin; m < chunk.end; ++m) {
      const MovingMatch& match = moving_[m];
      const Eigen::Vector3d n(match.n[0], match.n[1], match.n[2]);
      if (linearize) row.setZero();
      const Eigen::Vector3d q_i = end_of(match.p_i, match.knot_i, match.alpha_i, n, 1.0);
      const Eigen::Vector3d q_j = end_of(match.p_j, match.knot_j, match.alpha_j, n, -1.0);
      const double r = n.dot(q_i - q_j);
      out.cost += 0.5 * r * r;
      ++out.residuals;
      if (linearize) {
        rows.row(static_cast<long>(m - chunk.begin)) = row.transpose();
        residuals[static_cast<long>(m - chunk.begin)] = r;
      }
    }
    if (linearize) {
      out.hessian = Eigen::MatrixXd::Zero(K, K);
      out.hessian.selfadjointView<Eigen::Lower>().rankUpdate(rows.transpose());
      out.hessian = out.hessian.selfadjointView<Eigen::Lower>();
      out.gradient.noalias() = rows.transpose() * residuals;
    }
  });

  NormalEquations total;
  if (linearize) {
    total.hessian = Eigen::MatrixXd::Zero(K, K);
    total.gradient = Eigen::VectorXd::Zero(K);
  }
  auto add = [&](const NormalEquations& part) {
    total.cost += part.cost;
    total.residuals += part.residuals;
    if (linearize) {
      total.hessian += part.hessian;
      total.gradient += part.gradient;
    }
  };
  for (const NormalEquations& part : rigid) add(part);    // in pair order
  for (const NormalEquations& part : partial) add(part);  // in chunk order: deterministic
  return total;
}

bool SolveLevenbergMarquardt(const MatchProblem& problem, int max_iterations,
                             std::vector<double>& k_hat, LmSummary& summary,
                             const std::atomic<bool>* cancel) {
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
    const double model_decrease =
        -(current.gradient.dot(step) + 0.5 * step.dot(current.hessian * step));
    const double actual_decrease = current.cost - candidate_cost;
    const double rho = model_decrease > 0 ? actual_decrease / model_decrease : -1.0;
    if (std::isfinite(candidate_cost) && rho > 1e-3) {
      k_hat = candidate;
      const double relative = actual_decrease / std::max(current.cost, 1e-300);
      radius = radius / std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
      decrease_factor = 2.0;
      summary.final_cost = candidate_cost;
      // Linearizing is the expensive evaluation: skip it when no step follows.
      if (relative <= 1e-6 || iteration + 1 == max_iterations) break;
      current = problem.Evaluate(k_hat, true);
      summary.final_cost = current.cost;
    } else {
      radius /= decrease_factor;
      decrease_factor *= 2.0;
      if (radius < 1e-32) break;
    }
  }
  return std::isfinite(summary.final_cost);
}

}  // namespace selfcal::calib
