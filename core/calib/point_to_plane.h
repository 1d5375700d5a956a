// Stage 6: the paper's point-to-plane cost over all matches,
//   c = [tr(k_hat, j_i) p_i - tr(k_hat, j_j) p_j] . n(q_i),   e = sum c^2,
// with n(q_i) the oriented normal of this iteration's projection, held fixed while the
// parameters move (the paper does not differentiate the normal either: it is recomputed by the
// next ICP iteration). CostKind (calibrate.h) may replace n(q_i) by n(q_j) or by the normalized
// sum of both (docs/engine.md, deviation 13); everything below holds for any fixed n.
//
// MatchProblem evaluates it the fast way:
//  - a pair of single-pose scans (depth cameras) is reduced to the exact quadratic form of its cost
//    in the two poses (rigid_pair.h): O(1) per pair per evaluation, and no match is kept;
//  - other matches (line scanners, LiDARs: a pose per column or point) are evaluated one by one
//    through the poses of their scans' knots (pose_knots.h): forward kinematics and the 6 x K
//    Jacobian run once per knot, a match's derivative is
//    d c / d k = sum over its knots w (n, q_w x n) . J_w   (signs: + for i, - for j),
//    and J^T J is accumulated by rank updates of stacked rows.
// Sums run over fixed chunks (or pairs) reduced in order: the result does not depend on the
// thread count.
#pragma once

#include <Eigen/Core>
#include <atomic>
#include <functional>
#include <span>
#include <vector>

#include "core/calib/chain.h"
#include "core/calib/matching.h"
#include "core/calib/pose_knots.h"
#include "core/calib/projection.h"
#include "core/calib/rigid_pair.h"
#include "core/calib/robust_loss.h"

namespace selfcal::calib {

// The weights w with n . d p_base / d k = w^T J, for a point r = R_base_sensor p_sensor (base
// axes), a normal n held fixed and the pose Jacobian J (rows d t, omega; core/model/jacobian.h):
// w = (n, r x n), since n . (d t + omega x r) = n . d t + omega . (r x n). This is
// n^T ChainPointJacobian contracted before chaining: 6 multiply-adds per column of the transposed
// Jacobian the engine keeps, instead of 9 for the 3 x K point Jacobian and 3 for n^T (2 to 5 times
// faster per point: docs/kinematics.md, "Points"). Tests check that both agree.
inline Eigen::Matrix<double, 6, 1> PointToPlaneWeights(const Eigen::Vector3d& n,
                                                       const Eigen::Vector3d& r) {
  Eigen::Matrix<double, 6, 1> w;
  w << n, r.cross(n);
  return w;
}

// The cost of the frozen matches at some k_hat.
struct Evaluation {
  double cost = 0;  // 1/2 sum r^2 (normalized units), as Ceres reports it
  std::size_t residuals = 0;
};

// The cost and its Gauss-Newton linearization at some k_hat.
struct NormalEquations {
  Eigen::MatrixXd hessian;   // J^T J over the free parameters
  Eigen::VectorXd gradient;  // J^T r
  double cost = 0;           // 1/2 sum r^2 (normalized units), as Ceres reports it
  std::size_t residuals = 0;
};

// A match with everything the cost needs, frozen for one ICP iteration.
struct FrozenMatch {
  std::uint32_t dataset_i, point_i, dataset_j, point_j;
  float nx, ny, nz;    // the match's normal (MatchNormal)
  float weight = 1.f;  // the robust loss's weight (robust_loss.h): the residual is sqrt(w) c
};

class MatchProblem {
 public:
  // `free` lists the flat parameter indices being optimized (unmasked), the chain's intrinsics
  // last (every one of them); `knots` has one entry per dataset. `keep_all_matches`: also keep the
  // matches of reduced pairs (the reference solver builds one residual per match). `cost`: which
  // normal a match's residual uses.
  MatchProblem(const std::vector<Dataset>& datasets, const Chain& chain,
               const std::vector<PoseKnots>& knots, std::vector<std::size_t> free, int threads,
               bool keep_all_matches, CostKind cost = CostKind::kPaper);
  // Freezes the matches of `pairs` (match_pair(p) gives those of pairs[p], called in parallel)
  // and their normals from `clouds` (MatchNormal), projected at k_hat. Moving matches read their
  // normals from `clouds` and their points from the datasets at every evaluation: both must stay
  // as they are until the next SetMatches or Clear (with intrinsics, the points corrected at
  // k_hat's, CorrectPoints).
  void SetMatches(const std::vector<std::pair<std::uint32_t, std::uint32_t>>& pairs,
                  const std::function<PairMatches(std::size_t)>& match_pair,
                  const std::vector<ProjectedCloud>& clouds, const std::vector<double>& k_hat);
  // The loss the next SetMatches weights its matches with (default: squared, every weight 1).
  void SetLoss(const RobustLoss& loss) { loss_ = loss; }
  // The noise whose expected part the next SetMatches takes out of the rigid pairs' cost
  // (rigid_pair.h; default: none, the paper's cost).
  void SetRayNoise(const RayNoise& noise) { ray_noise_ = noise; }
  // The fraction of the expected noise the last SetMatches took out (0 without RayNoise).
  double NoiseFraction() const { return noise_fraction_; }
  // Frees the matches (their storage too).
  void Clear();
  // With keep_all_matches, every frozen match (else empty).
  const std::vector<FrozenMatch>& matches() const { return matches_; }
  std::size_t MatchCount() const { return match_count_; }
  // The sum of the frozen matches' weights (MatchCount() for the squared loss): the cost's
  // weighted RMS is sqrt(2 cost / WeightSum()).
  double WeightSum() const { return weight_sum_; }
  // Valid matches per dataset (both ends counted).
  const std::vector<std::size_t>& MatchesPerDataset() const { return per_dataset_; }
  const std::vector<std::size_t>& free() const { return free_; }

  // The cost at k_hat: one pose per knot, no Jacobian.
  Evaluation Evaluate(const std::vector<double>& k_hat) const;
  // The cost at k_hat and J^T J, J^T r over the free parameters (the expensive evaluation: a
  // Jacobian per knot). Its cost equals Evaluate()'s bit for bit.
  NormalEquations Linearize(const std::vector<double>& k_hat) const;

 private:
  struct KnotPoses;
  // The matches of scans i and j, which move while measuring, with their knots, as chunks.
  void AppendMovingMatches(PairMatches&& pair, std::vector<float>&& weights);
  // Takes the expected noise out of the rigid pairs (rigid_pair.h, deviation 23): the fraction
  // of it the matches show, sum r0^2 / sum v0 at most 1. Nearest-neighbour matching pairs a
  // point with the neighbour its own noise moved it towards, and the normal follows the noise
  // of the points it was computed from, so the residuals hold less of the noise than v says.
  void RemoveExpectedNoise();
  // The poses (and Jacobians) of the knots of every scan that has a match.
  KnotPoses PosesAt(const std::vector<double>& k_hat, bool with_jacobians) const;
  bool HasMatches(std::size_t d) const { return d < per_dataset_.size() && per_dataset_[d] > 0; }
  // One term per reduced rigid pair and per chunk of moving matches, summed in that order so the
  // sums do not depend on the thread count.
  std::vector<NormalEquations> RigidPairTerms(const KnotPoses& poses, bool linearize) const;
  std::vector<NormalEquations> MovingChunkTerms(const KnotPoses& poses, bool linearize) const;
  NormalEquations Sum(const KnotPoses& poses, bool linearize) const;

  const std::vector<Dataset>& datasets_;
  const Chain& chain_;
  const std::vector<PoseKnots>& knots_;
  std::vector<std::size_t> free_;
  int threads_;
  bool keep_all_matches_;
  CostKind cost_;
  RobustLoss loss_;
  RayNoise ray_noise_;
  double noise_fraction_ = 0;            // of the expected noise the last SetMatches took out
  std::vector<std::size_t> first_knot_;  // per dataset: index of its first knot over all knots
  std::vector<RigidPairCost> rigid_pairs_;
  // The matches of the pairs of scans that move while measuring, as they were matched (not
  // copied): their points by index into the two scans, 8 bytes a match, where a LiDAR keeps tens
  // of millions of them. Each evaluation reads their coordinates and knots from the scans
  // (pose_knots.h) and a match's normal from the clouds it was matched in (MatchNormal).
  std::vector<PairMatches> moving_;
  // The robust loss's weight of each of their matches, per pair (robust_loss.h: cost w c^2 / 2);
  // empty when every weight is 1.
  std::vector<std::vector<float>> moving_weights_;
  const std::vector<ProjectedCloud>* clouds_ = nullptr;  // of the last SetMatches
  std::vector<FrozenMatch> matches_;
  struct Chunk {
    std::size_t pair;        // in moving_: a chunk never crosses pairs
    std::size_t begin, end;  // of its matches
  };
  std::vector<Chunk> chunks_;
  std::size_t match_count_ = 0;
  double weight_sum_ = 0;
  // The free intrinsics at SetMatches (k_hat's) and their (sigma, omega, lambda), normalized.
  std::vector<double> intrinsics_start_;
  IntrinsicValues intrinsic_values_ = IntrinsicValues::Zero();
  std::vector<std::size_t> per_dataset_;
};

// Own Levenberg-Marquardt on MatchProblem (fast mode). Mirrors Ceres' defaults: trust-region
// radius 1e4, diagonal of J^T J clamped to [1e-6, 1e32], function tolerance 1e-6, gradient
// tolerance 1e-10, parameter tolerance 1e-8. Returns false when the cost became non-finite.
// Stops after the current step when *cancel becomes true (an abort must not wait for the solve).
// `lower`: the least value of each free parameter (LowerBounds of joint_correction.h; empty =
// none); a step that would cross one holds that parameter at it and solves the rest again.
struct LmSummary {
  int iterations = 0;
  double initial_cost = 0, final_cost = 0;
};
bool SolveLevenbergMarquardt(const MatchProblem& problem, int max_iterations,
                             std::vector<double>& k_hat, LmSummary& summary,
                             std::span<const double> lower = {},
                             const std::atomic<bool>* cancel = nullptr);

}  // namespace selfcal::calib
