// Stage 3: the noise and edge filter of the paper's "Projection and Validation":
//   o(p_ij) = sum_{a=-n..n} sum_{b=-m..m} |v_ij . v_{i+a,j+b}| / ((2n+1)(2m+1)),
// points with o < g_min (and points without a normal) are removed: Q = D \ O.
// n runs along rows (the grid's first index), m along columns. Neighbours outside the grid or
// without a normal contribute 0, so points beside holes and at the border are removed as noise
// (the paper does not say; this is the conservative reading).
#pragma once

#include <vector>

#include "core/calib/dataset.h"
#include "core/calib/projection.h"

namespace selfcal::calib {

// Per cell, the sum of |n_i . n_k| over the (2n + 1) x (2m + 1) window's cells k that have a
// normal (the cell itself among them); 0 where the cell has none.
std::vector<double> NormalOverlapSums(const ProjectedCloud& cloud, int n, int m);

// Fills cloud.keep, and cloud.boundary by MarkCoverageBoundary.
void FilterNoiseAndEdges(ProjectedCloud& cloud, int n, int m, double g_min);

// DELIBERATE DEVIATION (docs/engine.md, deviation 10), not in the paper: marks the points of Q
// on the border of the scan's coverage, cloud.boundary[i] = 1 when i is in Q and one of its 8
// grid neighbours (r +- 1, c +- 1) is outside the grid or not in Q (no measurement, no normal,
// or removed by the filter). The nearest neighbour in Q_j of a point that Q_j did not see (past
// the end of a line scanner's strip, behind an occlusion, in a filtered hole) is such a border
// point, up to d_max away; Turk and Levoy ("Zippered polygon meshes from range images",
// SIGGRAPH 1994) reject those pairs. Match rejection uses the flags of Q_j (RejectMatches).
void MarkCoverageBoundary(ProjectedCloud& cloud);

// DELIBERATE DEVIATION (docs/engine.md, deviation 12), for depth cameras: the border of what the
// scan measured, not of what the noise filter kept. cloud.boundary[i] = 1 when i is in Q and its
// (2 window_rows + 1) x (2 window_cols + 1) window reaches outside the grid, a cell without a
// measurement, or a depth discontinuity: a measured cell farther from a measured 4-neighbour
// than the step allows at the larger of their ranges (from the pose's sensor origin):
// base + (per_range + pitches * pitch) * range, pitch the scan's median angular spacing of row
// neighbours (a surface seen at a grazing angle spreads its samples by several). The holes a
// noisy camera's filter punches into Q (it keeps 13-37 % of the points, scattered) are not
// border; a silhouette, an occlusion shadow, the image's edge and no return still are, and the
// filter's band along them lies within the window (the filter's, grown by one).
struct SurfaceStep {
  float base = 0;       // normalized units
  float per_range = 0;  // per normalized unit of range
  float pitches = 0;    // multiples of the scan's own sample spacing
};
void MarkSurfaceBoundary(const Dataset& dataset, ProjectedCloud& cloud, int window_rows,
                         int window_cols, const SurfaceStep& step);

}  // namespace selfcal::calib
