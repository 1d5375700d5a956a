// DELIBERATE DEVIATION (docs/engine.md, deviation 14): a robust loss on the point-to-plane
// residuals, as iteratively reweighted least squares. The paper minimizes sum c^2; a match
// between things that are not one surface (a person who walked through, a box that moved,
// flying pixels between two depth layers, the arm's own links) enters it with its full square,
// up to d_max^2. With a robust loss each match's residual c is weighted by
//   w = 1 / (1 + (c / s)^2)   (Cauchy's kernel, the weight of rho(c) = s^2 / 2 log(1 + (c/s)^2)),
// s = loss_width * sqrt(sigma(q_i)^2 + sigma(q_j)^2), sigma = sigma_abs + sigma_rel * range the
// sensor file's noise at each point's range (the noise of the difference of two measurements).
// The weight is computed from the residual when the matches are frozen for an ICP iteration and
// held fixed during that iteration's Levenberg-Marquardt solve, as the normals are (deviation 4):
// the cost stays a weighted sum of squares, so the rigid-pair reduction stays exact (w multiplies
// each match's contribution to M, g and c0, rigid_pair.h) and the ICP loop is the IRLS loop.
#pragma once

#include <vector>

#include "core/calib/calibrate.h"
#include "core/calib/dataset.h"
#include "core/calib/matching.h"
#include "core/calib/projection.h"

namespace selfcal::calib {

// The loss of one calibration, in normalized units.
struct RobustLoss {
  LossKind kind = LossKind::kSquared;
  double width = 2.3849;  // s in multiples of the match's sigma
  double sigma_abs = 0;   // normalized units (m / scale)
  double sigma_rel = 0;   // per unit of range
  // False for the squared loss and for a sensor without noise (no scale): every weight is 1.
  bool Active() const { return kind != LossKind::kSquared && (sigma_abs > 0 || sigma_rel > 0); }
};
RobustLoss MakeRobustLoss(const CalibrationOptions& options, double scale);

// Cauchy's weight of residual c at kernel scale s > 0.
inline double CauchyWeight(double residual, double scale) {
  const double u = residual / scale;
  return 1.0 / (1.0 + u * u);
}

// The weight of every match of `matches` (empty when !loss.Active(): all 1), from its residual
// (q_i - q_j) . MatchNormal at the clouds' projection and the two points' sensor-frame ranges.
std::vector<float> MatchWeights(const RobustLoss& loss, CostKind cost, const PairMatches& matches,
                                const ProjectedCloud& cloud_i, const ProjectedCloud& cloud_j,
                                const Dataset& dataset_i, const Dataset& dataset_j, double scale);

// The sum of MatchWeights' `weights` for `count` matches (count when empty: all 1).
inline double SumOfWeights(const std::vector<float>& weights, std::size_t count) {
  if (weights.empty()) return static_cast<double>(count);
  double sum = 0;
  for (float weight : weights) sum += weight;
  return sum;
}

}  // namespace selfcal::calib
