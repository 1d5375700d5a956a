// Reference mode (`--solver reference`): the paper's implementation strategy. One Ceres residual
// block per match, each differentiating the point-to-plane residual through the full kinematic
// chain of both points with automatic differentiation, Levenberg-Marquardt over the unmasked
// parameters (SubsetManifold holds the masked ones constant). Slow by design: it is the baseline
// the fast mode is measured against and guards the fast path against drifting from the maths.
#pragma once

#include <vector>

#include "core/calib/point_to_plane.h"

namespace selfcal::calib {

// Minimizes the cost of `problem`'s frozen matches over the free parameters, starting at k_hat.
bool SolveReference(const std::vector<Dataset>& datasets, const Chain& chain,
                    const MatchProblem& problem, int max_iterations, int threads,
                    std::vector<double>& k_hat, LmSummary& summary);

}  // namespace selfcal::calib
