// Stage 2: normals from the organized grid, oriented against the view ray.
//
// The paper writes n_ij = m(p_{i-1,j}, p_{i,j-1}) + m(p_{i+1,j}, p_{i,j+1}), normalized, with
// m(p, q) = p x q / |p x q|: a cross product of the neighbour points themselves. Taken literally,
// that is the normal of the plane through the base origin and two neighbours, not of the surface.
// DELIBERATE DEVIATION: we cross the neighbours' differences to p_ij,
//   n_ij = m(p_{i-1,j} - p_ij, p_{i,j-1} - p_ij) + m(p_{i+1,j} - p_ij, p_{i,j+1} - p_ij),
// which is the surface normal the paper's text and Fig. 4 describe (both triangles turn the same
// way, so the two terms add). Where one triangle lacks a neighbour the other alone is used.
//
// Orientation (the paper's vn()): the paper flips n when n . o_t > 0, o_t the sensor origin. Read
// literally this compares n with the origin's position vector, which depends on where the base
// is. DELIBERATE DEVIATION: we compare with the view ray d = p_ij - o_t and flip when n . d > 0,
// so every normal faces the sensor that saw it.
#pragma once

#include "core/calib/dataset.h"
#include "core/calib/projection.h"

namespace selfcal::calib {

void ComputeNormals(const Dataset& dataset, ProjectedCloud& cloud);

// DELIBERATE DEVIATION (docs/engine.md, deviation 22), on request (--normals fit): the normal of
// the plane fitted to the valid points of the (2 n + 1) x (2 m + 1) grid window around each point,
// the fit along the view rays from the point's sensor origin o. A point p = o + t d (d the unit
// ray) on the plane n . p = k satisfies 1 / t = h . d with h = n / (k - n . o): linear in h, the
// noise in t alone (a range sensor's rays are exact, its noise lies along them). So h is the least
// squares solution of d_k^T h = 1 / t_k over the window, n = h / |h|, oriented as above. The
// neighbours' cross product of the paper is the normal of three noisy points, and a PCA normal's
// errors-in-variables tilt it away from the ray (noise along the ray spreads the points across
// the plane at a grazing angle); this fit uses the window's points and keeps the noise where the
// least squares model puts it. Points with fewer than 5 valid window points, or whose rays span
// no plane, get no normal.
void ComputeFittedNormals(const Dataset& dataset, ProjectedCloud& cloud, int n, int m);

}  // namespace selfcal::calib
