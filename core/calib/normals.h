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

}  // namespace selfcal::calib
