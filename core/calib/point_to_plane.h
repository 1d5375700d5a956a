// Stage 6: the paper's point-to-plane cost over all matches,
//   c = [tr(k_hat, j_i) p_i - tr(k_hat, j_j) p_j] . n(q_i),   e = sum c^2,
// with n(q_i) the oriented normal of this iteration's projection, held fixed while the
// parameters move (the paper does not differentiate the normal either: it is recomputed by the
// next ICP iteration).
//
// MatchProblem evaluates it the fast way (issue 5): every pose's transform and 6 x K Jacobian
// (pose_jacobian.h) once, then per match d c / d k = (n, q_i x n) . J_i - (n, q_j x n) . J_j.
// Matches between two single-pose scans are summed into a 12 x 12 block per pair first, so the
// K x K normal matrix costs O(1) per pair instead of O(K^2) per match. Sums run over fixed chunks
// reduced in order: the result does not depend on the thread count.
#pragma once

#include <atomic>

#include <Eigen/Core>
#include <vector>

#include "core/calib/chain.h"
#include "core/calib/matching.h"
#include "core/calib/projection.h"

namespace selfcal::calib {

struct NormalEquations {
  Eigen::MatrixXd hessian;   // J^T J over the free parameters
  Eigen::VectorXd gradient;  // J^T r
  double cost = 0;           // 1/2 sum r^2 (normalized units), as Ceres reports it
  std::size_t residuals = 0;
};

// A match with everything the cost needs, frozen for one ICP iteration.
struct FrozenMatch {
  std::uint32_t dataset_i, point_i, dataset_j, point_j;
  float nx, ny, nz;  // n(q_i)
};

class MatchProblem {
 public:
  // `free` lists the flat parameter indices being optimized (unmasked).
  MatchProblem(const std::vector<Dataset>& datasets, const Chain& chain, std::vector<std::size_t> free,
               int threads);
  // Freezes the matches and the normals n(q_i) of `clouds`.
  void SetMatches(const std::vector<PairMatches>& matches, const std::vector<ProjectedCloud>& clouds);
  const std::vector<FrozenMatch>& matches() const { return matches_; }
  std::size_t FreeCount() const { return free_.size(); }
  const std::vector<std::size_t>& free() const { return free_; }

  // Cost at k_hat, and J^T J, J^T r when `linearize`.
  NormalEquations Evaluate(const std::vector<double>& k_hat, bool linearize) const;

 private:
  const std::vector<Dataset>& datasets_;
  const Chain& chain_;
  std::vector<std::size_t> free_;
  int threads_;
  std::vector<FrozenMatch> matches_;
  struct Chunk {
    std::size_t begin, end;
    bool single_pose_pair;
  };
  std::vector<Chunk> chunks_;
};

// Own Levenberg-Marquardt on MatchProblem (fast mode). Mirrors Ceres' defaults: trust-region
// radius 1e4, diagonal of J^T J clamped to [1e-6, 1e32], function tolerance 1e-6, gradient
// tolerance 1e-10, parameter tolerance 1e-8. Returns false when the cost became non-finite.
// Stops after the current step when *cancel becomes true (an abort must not wait for the solve).
struct LmSummary {
  int iterations = 0;
  double initial_cost = 0, final_cost = 0;
};
bool SolveLevenbergMarquardt(const MatchProblem& problem, int max_iterations, std::vector<double>& k_hat,
                             LmSummary& summary, const std::atomic<bool>* cancel = nullptr);

}  // namespace selfcal::calib
