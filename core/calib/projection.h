// Stage 1 of Algorithm 1: project a dataset to the base frame along the chain,
// p_hat_B = tr(k_hat, j_hat_t) p_hat_E, and keep each pose's sensor origin o_B_t for orienting
// normals against the view ray. Results in normalized units, float structure-of-arrays.
#pragma once

#include <cstdint>
#include <vector>

#include "core/calib/chain.h"
#include "core/calib/dataset.h"
#include "core/calib/pose_knots.h"

namespace selfcal::calib {

struct ProjectedCloud {
  std::size_t rows = 0, cols = 0;
  std::vector<float> x, y, z;      // base frame, normalized; NaN = no measurement
  std::vector<float> nx, ny, nz;   // oriented unit normals (normals stage); NaN = none
  std::vector<std::uint8_t> keep;  // 1 = in Q (noise/edge filter stage), 0 = in O or invalid
  // 1 = a point of Q on the border of the scan's coverage: one of its 8 grid neighbours is
  // outside the grid or not in Q (noise/edge filter stage, MarkCoverageBoundary). Empty = not
  // computed. A match whose nearest neighbour is such a point is no correspondence
  // (docs/engine.md, deviation 10).
  std::vector<std::uint8_t> boundary;
  // The sensor origin of every pose, normalized: 3 floats a pose, or, for a cloud projected
  // through its scan's knots, 3 doubles a knot, blended as the poses are (a LiDAR has a pose per
  // point: 12 bytes a point otherwise). Read them with Origin().
  std::vector<float> origin;
  std::vector<Eigen::Vector3d> knot_origin;
  const PoseKnots* knots = nullptr;  // with knot_origin: the scan's, which outlive the cloud

  bool Valid(std::size_t i) const { return x[i] == x[i]; }
  bool HasNormal(std::size_t i) const { return nx[i] == nx[i]; }
  Eigen::Vector3f Point(std::size_t i) const { return {x[i], y[i], z[i]}; }
  Eigen::Vector3f Normal(std::size_t i) const { return {nx[i], ny[i], nz[i]}; }
  std::size_t PoseCount() const {
    return knots != nullptr ? knots->segment.size() : origin.size() / 3;
  }
  Eigen::Vector3f Origin(std::size_t pose) const {
    if (knots == nullptr) return {origin[3 * pose], origin[3 * pose + 1], origin[3 * pose + 2]};
    const std::uint32_t a = knots->segment[pose];
    return Blend(knot_origin[a], knot_origin[knots->SecondKnot(a)], knots->alpha[pose])
        .cast<float>();
  }
};

// Every valid point of `dataset` in the base frame, in double, in the units of `chain` and `k`:
// with chain.scale = 1 and raw parameters, metres, as the normalization scale s needs
// (NormalizationScale of core/model/normalization.h).
std::vector<Eigen::Vector3d> BasePoints(const Dataset& dataset, const Chain& chain,
                                        const double* k);

// Projects every point; normals and keep are sized but left empty (NaN / 0). With `knots`, poses
// between knots are interpolated (pose_knots.h, fast mode); without, every pose is exact.
ProjectedCloud ProjectDataset(const Dataset& dataset, const Chain& chain, const double* k_hat,
                              const PoseKnots* knots = nullptr);

}  // namespace selfcal::calib
