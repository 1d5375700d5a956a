// Stage 3: the noise and edge filter of the paper's "Projection and Validation":
//   o(p_ij) = sum_{a=-n..n} sum_{b=-m..m} |v_ij . v_{i+a,j+b}| / ((2n+1)(2m+1)),
// points with o < g_min (and points without a normal) are removed: Q = D \ O.
// n runs along rows (the grid's first index), m along columns. Neighbours outside the grid or
// without a normal contribute 0, so points beside holes and at the border are removed as noise
// (the paper does not say; this is the conservative reading).
#pragma once

#include "core/calib/projection.h"

namespace selfcal::calib {

void FilterNoiseAndEdges(ProjectedCloud& cloud, int n, int m, double g_min);

}  // namespace selfcal::calib
