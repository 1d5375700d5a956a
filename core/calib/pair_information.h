// The information the engine's own cost gets from each pair of scans: the normal equations
// J^T J, J^T r of a pair's matches at some k_hat (point_to_plane.h), as one ICP iteration's data
// association makes them there (project, normals, noise/edge filter, match, reject). The
// covariance's jackknife (covariance.h) sums them at the solution; the scan planner
// (core/plan/information_planner.h) at the nominal model, on noise-free simulated scans of
// candidate views, to choose the views whose pairs pin the parameters down best.
#pragma once

#include <cstddef>
#include <vector>

#include "core/calib/calibrate.h"
#include "core/calib/covariance.h"
#include "core/calib/pair_matching.h"
#include "core/calib/point_to_plane.h"
#include "core/calib/robust_loss.h"
#include "core/calib/sensor_intrinsics.h"
#include "core/util/expected.h"

namespace selfcal::calib {

// One MatchProblem per pair of `pairs` at k_hat (pairs in parallel; every term independent of
// the thread count), weighted by `loss`. `matcher` must have been prepared at k_hat. Pairs
// without a match are left out.
std::vector<PairNormalEquations> LinearizeEachPair(
    const std::vector<Dataset>& datasets, const Chain& chain, const std::vector<PoseKnots>& knots,
    const PairMatcher& matcher, const std::vector<std::size_t>& free,
    const std::vector<DatasetPair>& pairs, const std::vector<double>& k_hat, int threads,
    CostKind cost, const RobustLoss& loss);

// The normalization scale s the engine uses for `datasets` (the paper's "Normalization"):
// from the first fit dataset projected with `model`. 0 when it cannot be computed.
double EngineScale(const std::vector<Dataset>& datasets, const RobotModel& model);

struct PairInformation {
  double scale_m = 0;  // s
  // Flat parameter indices of model.mask, in order, then the held intrinsics' columns.
  std::vector<std::size_t> free;
  std::size_t held = 0;                    // how many of `free` are held (the last ones)
  Eigen::VectorXd held_sd;                 // their 1 sigma, normalized units
  std::vector<PairNormalEquations> pairs;  // normalized units; pairs without a match left out

  std::size_t EstimatedCount() const { return free.size() - held; }
};

// The pairs' normal equations at `model` (k_hat = its parameters, the squared loss, no joint
// correction), every pair of `pairs` matched as the engine's first iteration would from
// `model`, with columns for the intrinsics `held` names at their assumed values (the consider
// covariance's, covariance.h). The error names what is inconsistent (joint counts, no valid
// point, no scale).
Expected<PairInformation> LinearizePairsAt(const std::vector<Dataset>& datasets,
                                           const RobotModel& model,
                                           const CalibrationOptions& options,
                                           const std::vector<DatasetPair>& pairs,
                                           const HeldIntrinsics& held = {});

}  // namespace selfcal::calib
