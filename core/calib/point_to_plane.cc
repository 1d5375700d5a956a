#include "core/calib/point_to_plane.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "core/calib/parallel.h"
#include "core/util/release.h"

namespace selfcal::calib {

namespace {

constexpr std::size_t kChunkSize = 8192;

using Pose34 = Eigen::Matrix<double, 3, 4>;
// Transposed (K x 6, column-major): J^T w is six contiguous K-long multiply-adds.
using PoseJacobianTransposed = Eigen::Matrix<double, Eigen::Dynamic, 6>;

PoseJacobian FreeColumns(const PoseJacobian& full, const std::vector<std::size_t>& free) {
  PoseJacobian result(6, static_cast<long>(free.size()));
  for (std::size_t c = 0; c < free.size(); ++c)
    result.col(static_cast<long>(c)) = full.col(static_cast<long>(free[c]));
  return result;
}

bool IsRigid(const Dataset& dataset) { return dataset.layout == PoseLayout::kOnePerScan; }

// The intrinsics a moving match's points move with (sensor_intrinsics.h): their free values at
// the matching (the points' correction, normalized) and the change since. Exact: p_c is linear
// in them.
struct IntrinsicsChange {
  const SensorIntrinsics* model = nullptr;  // null: none free
  IntrinsicValues values = IntrinsicValues::Zero();
  Eigen::Vector3d change = Eigen::Vector3d::Zero();  // entries 0 .. Count() - 1
};

// The scan one end of a moving match lies in: its points (sensor frame, as recorded) and knots.
struct ScanOfEnd {
  const Dataset* dataset;
  const PoseKnots* knots;
  std::size_t first_knot;  // index of its first knot over all datasets' knots
};

// A chunk of moving matches, all of one pair of scans, with their weights (null: all 1) and the
// clouds their normals come from.
struct MovingChunk {
  const std::uint32_t *point_i, *point_j;  // its matches' points in scans i and j
  long count;
  const float* weights;
  ScanOfEnd scan_i, scan_j;
  const ProjectedCloud *cloud_i, *cloud_j;
  CostKind cost;
  double Weight(long m) const { return weights != nullptr ? static_cast<double>(weights[m]) : 1.0; }
  Eigen::Vector3d Normal(long m) const {
    return MatchNormal(cost, *cloud_i, point_i[m], *cloud_j, point_j[m]).cast<double>();
  }
};

// One end of a moving match, q = (1 - alpha) T_a p + alpha T_b p (knots a and b = a + 1), and
// the point rotated into base axes by each knot, r_w = R_w p, for the derivative; D = d p / d
// theta with intrinsics.
struct MatchEnd {
  Eigen::Vector3d r_a, r_b, q;  // r_b only when alpha != 0
  Eigen::Matrix3d D;
  std::uint32_t a;  // over all datasets' knots
  double alpha;
};

MatchEnd ProjectEnd(const std::vector<Pose34>& transforms, const ScanOfEnd& scan,
                    std::uint32_t point, double inverse_scale, const IntrinsicsChange& intrinsics) {
  const Dataset& dataset = *scan.dataset;
  const std::size_t pose = dataset.PoseOf(point);
  MatchEnd end;
  end.a = static_cast<std::uint32_t>(scan.first_knot + scan.knots->segment[pose]);
  end.alpha = scan.knots->alpha[pose];
  Eigen::Vector3d p =
      Eigen::Vector3d(dataset.x[point], dataset.y[point], dataset.z[point]) * inverse_scale;
  if (intrinsics.model != nullptr) {
    end.D = intrinsics.model->PointDerivative(p, intrinsics.values);
    p += end.D * intrinsics.change;
  }
  const Pose34& T_a = transforms[end.a];
  end.r_a = T_a.leftCols<3>() * p;
  const Eigen::Vector3d q_a = end.r_a + T_a.col(3);
  if (end.alpha == 0.0) {
    end.q = q_a;
    return end;
  }
  const Pose34& T_b = transforms[end.a + 1];
  end.r_b = T_b.leftCols<3>() * p;
  end.q = (1.0 - end.alpha) * q_a + end.alpha * (end.r_b + T_b.col(3));
  return end;
}

double MovingResidual(const Eigen::Vector3d& n, const MatchEnd& end_i, const MatchEnd& end_j) {
  return n.dot(end_i.q - end_j.q);
}

// The cost of a chunk of moving matches.
NormalEquations EvaluateMoving(const MovingChunk& chunk, const std::vector<Pose34>& transforms,
                               double inverse_scale, const IntrinsicsChange& intrinsics) {
  NormalEquations out;
  for (long m = 0; m < chunk.count; ++m) {
    const MatchEnd end_i =
        ProjectEnd(transforms, chunk.scan_i, chunk.point_i[m], inverse_scale, intrinsics);
    const MatchEnd end_j =
        ProjectEnd(transforms, chunk.scan_j, chunk.point_j[m], inverse_scale, intrinsics);
    const double r = MovingResidual(chunk.Normal(m), end_i, end_j);
    out.cost += 0.5 * chunk.Weight(m) * r * r;
    ++out.residuals;
  }
  return out;
}

// Adds sign * d(n . q)/dk of one end to `row`: the sum over its knots w of
// weight_w * PointToPlaneWeights(n, r_w) . J_w, and with m intrinsics (the last m entries)
// n . ((1 - alpha) R_a + alpha R_b) D.
void AddEndDerivative(const std::vector<PoseJacobianTransposed>& jacobians,
                      const std::vector<Pose34>& transforms, const MatchEnd& end,
                      const Eigen::Vector3d& n, double sign, long m, Eigen::VectorXd& row) {
  const std::uint32_t a = end.a;
  const double alpha = end.alpha;
  auto through = [&](std::uint32_t knot, const Eigen::Vector3d& r, double weight) {
    row.noalias() += jacobians[knot] * (sign * weight * PointToPlaneWeights(n, r));
  };
  through(a, end.r_a, 1.0 - alpha);
  if (alpha != 0.0) through(a + 1, end.r_b, alpha);
  if (m == 0) return;
  Eigen::Vector3d n_sensor = (1.0 - alpha) * (transforms[a].leftCols<3>().transpose() * n);
  if (alpha != 0.0) n_sensor += alpha * (transforms[a + 1].leftCols<3>().transpose() * n);
  row.tail(m) += sign * (end.D.transpose() * n_sensor).head(m);
}

// The cost of a chunk of moving matches and its J^T J, J^T r by a rank update of their stacked
// rows.
NormalEquations LinearizeMoving(const MovingChunk& chunk, const std::vector<Pose34>& transforms,
                                const std::vector<PoseJacobianTransposed>& jacobians,
                                double inverse_scale, long K, const IntrinsicsChange& intrinsics) {
  const long free_intrinsics =
      intrinsics.model != nullptr ? static_cast<long>(intrinsics.model->Count()) : 0;
  const long count = chunk.count;
  Eigen::MatrixXd rows(count, K);
  Eigen::VectorXd residuals(count);
  Eigen::VectorXd row(K);
  NormalEquations out;
  for (long m = 0; m < count; ++m) {
    const Eigen::Vector3d n = chunk.Normal(m);
    const MatchEnd end_i =
        ProjectEnd(transforms, chunk.scan_i, chunk.point_i[m], inverse_scale, intrinsics);
    const MatchEnd end_j =
        ProjectEnd(transforms, chunk.scan_j, chunk.point_j[m], inverse_scale, intrinsics);
    row.setZero();
    AddEndDerivative(jacobians, transforms, end_i, n, 1.0, free_intrinsics, row);
    AddEndDerivative(jacobians, transforms, end_j, n, -1.0, free_intrinsics, row);
    const double r = MovingResidual(n, end_i, end_j);
    const double weight = chunk.Weight(m);
    out.cost += 0.5 * weight * r * r;
    ++out.residuals;
    const double root_weight = std::sqrt(weight);  // rows of sum w r^2
    rows.row(m) = root_weight * row.transpose();
    residuals[m] = root_weight * r;
  }
  out.hessian = Eigen::MatrixXd::Zero(K, K);
  out.hessian.selfadjointView<Eigen::Lower>().rankUpdate(rows.transpose());
  out.hessian = out.hessian.selfadjointView<Eigen::Lower>();
  out.gradient.noalias() = rows.transpose() * residuals;
  return out;
}

}  // namespace

MatchProblem::MatchProblem(const std::vector<Dataset>& datasets, const Chain& chain,
                           const std::vector<PoseKnots>& knots, std::vector<std::size_t> free,
                           int threads, bool keep_all_matches, CostKind cost)
    : datasets_(datasets),
      chain_(chain),
      knots_(knots),
      free_(std::move(free)),
      threads_(threads),
      keep_all_matches_(keep_all_matches),
      cost_(cost) {
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
  clouds_ = &clouds;
  // The datasets' points are corrected at k_hat's intrinsics (sensor_intrinsics.h).
  const std::span<const double> intrinsics = chain_.FreeIntrinsics(k_hat.data());
  intrinsics_start_.assign(intrinsics.begin(), intrinsics.end());
  intrinsic_values_ = chain_.intrinsics.Values(intrinsics, 1.0);
  const RigidPairIntrinsics pair_intrinsics{chain_.intrinsics, intrinsic_values_};
  std::vector<Eigen::Matrix<double, 3, 4>> rigid_pose(datasets_.size());
  for (std::size_t d = 0; d < datasets_.size(); ++d) {
    double joints[kMaxJoints];
    if (IsRigid(datasets_[d])) {
      rigid_pose[d] =
          chain_.Pose(k_hat.data(), datasets_[d].Joints(0, joints)).matrix().topRows<3>();
    }
  }
  // Rigid pairs are reduced as soon as they are matched, so their matches never pile up.
  std::vector<RigidPairCost> reduced(pairs.size());
  std::vector<PairMatches> kept(pairs.size());
  std::vector<std::vector<float>> weights(pairs.size());  // empty: all 1 (robust_loss.h)
  std::vector<double> pair_weight_sum(pairs.size());
  ParallelFor(pairs.size(), threads_, [&](std::size_t p) {
    PairMatches matches = match_pair(p);
    const auto [i, j] = pairs[p];
    weights[p] = MatchWeights(loss_, cost_, matches, clouds[i], clouds[j], datasets_[i],
                              datasets_[j], chain_.scale);
    pair_weight_sum[p] = SumOfWeights(weights[p], matches.size());
    if (IsRigid(datasets_[i]) && IsRigid(datasets_[j])) {
      reduced[p] = ReduceRigidPair(matches, cost_, clouds[i], clouds[j], datasets_[i], datasets_[j],
                                   chain_.scale, rigid_pose[i], rigid_pose[j], weights[p],
                                   pair_intrinsics, ray_noise_);
      if (!keep_all_matches_) {
        weights[p] = {};  // reduced: memory bounded by the points, not the matches
        return;
      }
    }
    kept[p] = std::move(matches);
  });
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    const auto [i, j] = pairs[p];
    const bool rigid = IsRigid(datasets_[i]) && IsRigid(datasets_[j]);
    const std::size_t count = rigid ? reduced[p].matches : kept[p].size();
    match_count_ += count;
    weight_sum_ += pair_weight_sum[p];  // in pair order: the same sum for any thread count
    per_dataset_[i] += count;
    per_dataset_[j] += count;
    const PairMatches& pair = kept[p];
    const ProjectedCloud& cloud_i = clouds[i];
    const ProjectedCloud& cloud_j = clouds[j];
    if (keep_all_matches_) {  // the reference solver's residuals
      for (std::size_t k = 0; k < pair.size(); ++k) {
        const std::uint32_t u = pair.point_i[k], v = pair.point_j[k];
        const Eigen::Vector3f n = MatchNormal(cost_, cloud_i, u, cloud_j, v);
        const float weight = weights[p].empty() ? 1.f : weights[p][k];
        matches_.push_back({i, u, j, v, n.x(), n.y(), n.z(), weight});
      }
    }
    if (rigid) {
      if (reduced[p].matches > 0) rigid_pairs_.push_back(std::move(reduced[p]));
      continue;
    }
    AppendMovingMatches(std::move(kept[p]), std::move(weights[p]));
  }
  RemoveExpectedNoise();
}

void MatchProblem::RemoveExpectedNoise() {
  double squares = 0, expected = 0;
  for (const RigidPairCost& pair : rigid_pairs_) {
    if (!pair.noise) continue;
    squares += pair.c0;
    expected += pair.noise->v0;
  }
  noise_fraction_ = expected > 0 ? std::min(1.0, squares / expected) : 0.0;
  for (RigidPairCost& pair : rigid_pairs_) calib::RemoveExpectedNoise(pair, noise_fraction_);
}

void MatchProblem::AppendMovingMatches(PairMatches&& pair, std::vector<float>&& weights) {
  if (pair.size() == 0) return;
  // Chunks never cross pairs and depend only on the matches: deterministic sums.
  for (std::size_t begin = 0; begin < pair.size(); begin += kChunkSize)
    chunks_.push_back({moving_.size(), begin, std::min(pair.size(), begin + kChunkSize)});
  moving_.push_back(std::move(pair));
  moving_weights_.push_back(std::move(weights));
}

void MatchProblem::Clear() {
  Release(rigid_pairs_);
  Release(moving_);
  Release(moving_weights_);
  clouds_ = nullptr;
  Release(matches_);
  Release(chunks_);
  match_count_ = 0;
  weight_sum_ = 0;
  per_dataset_.assign(datasets_.size(), 0);
}

struct MatchProblem::KnotPoses {
  std::vector<Pose34> transforms;                 // every knot's T_base_sensor
  std::vector<PoseJacobianTransposed> jacobians;  // ... and its Jacobian, when linearizing
  Eigen::VectorXd intrinsics_change;              // free intrinsics since SetMatches
};

MatchProblem::KnotPoses MatchProblem::PosesAt(const std::vector<double>& k_hat,
                                              bool with_jacobians) const {
  // One walk along the chain per knot, not per point.
  KnotPoses poses;
  const std::span<const double> intrinsics = chain_.FreeIntrinsics(k_hat.data());
  poses.intrinsics_change.resize(static_cast<long>(intrinsics.size()));
  for (std::size_t c = 0; c < intrinsics.size(); ++c) {  // 0 before the first SetMatches
    const double start = c < intrinsics_start_.size() ? intrinsics_start_[c] : intrinsics[c];
    poses.intrinsics_change[static_cast<long>(c)] = intrinsics[c] - start;
  }
  poses.transforms.resize(first_knot_.back());
  poses.jacobians.resize(with_jacobians ? first_knot_.back() : 0);
  ParallelFor(datasets_.size(), threads_, [&](std::size_t d) {
    // A scan without a match is never read: a pair's problem (pair_information.h) walks the
    // chain for its two scans only.
    if (!HasMatches(d)) return;
    PoseJacobian full;
    double buffer[kMaxJoints];
    for (std::size_t knot = 0; knot < knots_[d].KnotCount(); ++knot) {
      const PoseState joints = datasets_[d].Joints(knots_[d].knot_pose[knot], buffer);
      const std::size_t index = first_knot_[d] + knot;
      Transform3<double> T;
      if (with_jacobians) {
        chain_.PoseWithJacobian(k_hat.data(), joints, T, full);
        poses.jacobians[index] = FreeColumns(full, free_).transpose();
      } else {
        T = chain_.Pose(k_hat.data(), joints);
      }
      poses.transforms[index] = T.matrix().topRows<3>();
    }
  });
  return poses;
}

std::vector<NormalEquations> MatchProblem::RigidPairTerms(const KnotPoses& poses,
                                                          bool linearize) const {
  const long K = static_cast<long>(free_.size());
  std::vector<PoseEntriesJacobian> entries_jacobian(linearize ? datasets_.size() : 0);
  for (std::size_t d = 0; d < entries_jacobian.size(); ++d) {
    const std::size_t index = first_knot_[d];
    if (IsRigid(datasets_[d]) && HasMatches(d))
      entries_jacobian[d] =
          PoseEntriesDerivative(poses.transforms[index], poses.jacobians[index].transpose());
  }
  std::vector<NormalEquations> terms(rigid_pairs_.size());
  ParallelFor(rigid_pairs_.size(), threads_, [&](std::size_t p) {
    const RigidPairCost& pair = rigid_pairs_[p];
    NormalEquations& out = terms[p];
    if (linearize) {
      out.hessian = Eigen::MatrixXd::Zero(K, K);
      out.gradient = Eigen::VectorXd::Zero(K);
    }
    const Pose34& T_i = poses.transforms[first_knot_[pair.dataset_i]];
    const Pose34& T_j = poses.transforms[first_knot_[pair.dataset_j]];
    out.cost = 0.5 * RigidPairSquaredSum(pair, Eigen::Map<const PoseEntries>(T_i.data()),
                                         Eigen::Map<const PoseEntries>(T_j.data()),
                                         poses.intrinsics_change,
                                         linearize ? &entries_jacobian[pair.dataset_i] : nullptr,
                                         linearize ? &entries_jacobian[pair.dataset_j] : nullptr,
                                         &out.hessian, &out.gradient);
    out.residuals = pair.matches;
  });
  return terms;
}

std::vector<NormalEquations> MatchProblem::MovingChunkTerms(const KnotPoses& poses,
                                                            bool linearize) const {
  const double inverse_scale = 1.0 / chain_.scale;
  IntrinsicsChange intrinsics;
  if (!chain_.intrinsics.Empty()) {
    intrinsics.model = &chain_.intrinsics;
    intrinsics.values = intrinsic_values_;
    intrinsics.change.head(poses.intrinsics_change.size()) = poses.intrinsics_change;
  }
  std::vector<NormalEquations> terms(chunks_.size());
  auto scan = [&](std::uint32_t d) { return ScanOfEnd{&datasets_[d], &knots_[d], first_knot_[d]}; };
  ParallelFor(chunks_.size(), threads_, [&](std::size_t c) {
    const Chunk& at = chunks_[c];
    const PairMatches& pair = moving_[at.pair];
    const std::vector<float>& weights = moving_weights_[at.pair];
    const MovingChunk chunk{pair.point_i.data() + at.begin,
                            pair.point_j.data() + at.begin,
                            static_cast<long>(at.end - at.begin),
                            weights.empty() ? nullptr : weights.data() + at.begin,
                            scan(pair.dataset_i),
                            scan(pair.dataset_j),
                            &(*clouds_)[pair.dataset_i],
                            &(*clouds_)[pair.dataset_j],
                            cost_};
    terms[c] = linearize ? LinearizeMoving(chunk, poses.transforms, poses.jacobians, inverse_scale,
                                           static_cast<long>(free_.size()), intrinsics)
                         : EvaluateMoving(chunk, poses.transforms, inverse_scale, intrinsics);
  });
  return terms;
}

NormalEquations MatchProblem::Sum(const KnotPoses& poses, bool linearize) const {
  NormalEquations total;
  if (linearize) {
    const long K = static_cast<long>(free_.size());
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
  for (const NormalEquations& part : RigidPairTerms(poses, linearize)) add(part);    // pair order
  for (const NormalEquations& part : MovingChunkTerms(poses, linearize)) add(part);  // chunks
  return total;
}

Evaluation MatchProblem::Evaluate(const std::vector<double>& k_hat) const {
  const NormalEquations total = Sum(PosesAt(k_hat, false), false);
  return {total.cost, total.residuals};
}

NormalEquations MatchProblem::Linearize(const std::vector<double>& k_hat) const {
  return Sum(PosesAt(k_hat, true), true);
}

namespace {

// The damped Gauss-Newton step from x, with every bounded parameter that it would take below its
// bound held there (an active set): such a parameter steps exactly to its bound and the others are
// solved again with that step fixed, until none crosses.
Eigen::VectorXd BoundedStep(const Eigen::MatrixXd& damped, const Eigen::VectorXd& gradient,
                            const Eigen::VectorXd& x, std::span<const double> lower) {
  Eigen::VectorXd step = damped.ldlt().solve(-gradient);
  if (lower.empty()) return step;
  const Eigen::Index K = x.size();
  std::vector<bool> held(static_cast<std::size_t>(K), false);
  for (Eigen::Index pass = 0; pass < K; ++pass) {
    bool crossed = false;
    for (Eigen::Index c = 0; c < K; ++c) {
      const auto i = static_cast<std::size_t>(c);
      if (!held[i] && x[c] + step[c] < lower[i]) held[i] = crossed = true;
    }
    if (!crossed) break;
    std::vector<Eigen::Index> open;
    Eigen::VectorXd fixed = Eigen::VectorXd::Zero(K);
    for (Eigen::Index c = 0; c < K; ++c) {
      const auto i = static_cast<std::size_t>(c);
      if (held[i]) {
        fixed[c] = lower[i] - x[c];
      } else {
        open.push_back(c);
      }
    }
    const Eigen::VectorXd rhs = -gradient - damped * fixed;
    step = fixed;
    if (open.empty()) break;
    const Eigen::VectorXd solved = damped(open, open).ldlt().solve(rhs(open));
    step(open) = solved;
  }
  return step;
}

}  // namespace

bool SolveLevenbergMarquardt(const MatchProblem& problem, int max_iterations,
                             std::vector<double>& k_hat, LmSummary& summary,
                             std::span<const double> lower, const std::atomic<bool>* cancel) {
  const auto& free = problem.free();
  const long K = static_cast<long>(free.size());
  NormalEquations current = problem.Linearize(k_hat);
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
    Eigen::VectorXd x(K);
    for (long c = 0; c < K; ++c) x[c] = k_hat[free[static_cast<std::size_t>(c)]];
    const Eigen::VectorXd step = BoundedStep(damped, current.gradient, x, lower);
    if (!step.allFinite()) return false;
    summary.iterations = iteration + 1;
    if (step.norm() <= 1e-8 * (x.norm() + 1e-8)) break;
    std::vector<double> candidate = k_hat;
    for (long c = 0; c < K; ++c) candidate[free[static_cast<std::size_t>(c)]] += step[c];
    const double candidate_cost = problem.Evaluate(candidate).cost;
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
      current = problem.Linearize(k_hat);
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
