// The sensor's measure calibrated with the arm (docs/engine.md, deviation 17): a scale and an
// offset of what the sensor measures along each ray, the intrinsics real units get wrong (a
// time-of-flight camera's depth scale and offset, a LiDAR's range offset, a line scanner's z
// scale). The engine corrects every recorded point
//   p_c = (1 + sigma) p + omega r,   r = p / m(p),
// m(p) the measure of the point: its depth z for depth cameras and line scanners (their rays have
// z = 1), its range |p| for a rotating LiDAR (unit rays). So the corrected measure is
// (1 + sigma) m + omega along the unchanged ray, linear in (sigma, omega): d p_c / d sigma = p,
// d p_c / d omega = r. A sensor whose true measure is m_true reads (1 + s) m_true + o has
// sigma = 1 / (1 + s) - 1 and omega = -o / (1 + s).
//
// In k_hat the free ones follow every other parameter (chain.h): sigma as is, omega divided by
// the normalization scale like every translation. The engine keeps the datasets' points corrected
// at the current estimate (CorrectPoints, once per ICP iteration with the joint correction's
// freeze), so projection, normals, matching and the cost read corrected points as they read raw
// ones; only the cost's derivative needs PointDerivative.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "core/calib/dataset.h"

namespace selfcal::calib {

// What the sensor measures along a ray: its depth z, or its range |p|.
enum class MeasureKind { kDepth, kRange };
MeasureKind MeasureKindOf(PoseLayout layout);  // LiDAR (one pose per point): range

struct SensorIntrinsics {
  bool scale = false;   // sigma free
  bool offset = false;  // omega free
  MeasureKind measure = MeasureKind::kDepth;

  std::size_t Count() const { return (scale ? 1 : 0) + (offset ? 1 : 0); }
  bool Empty() const { return Count() == 0; }
  // "sensor.depth_scale", "sensor.depth_offset" (a LiDAR: range_), in k_hat's order.
  std::vector<std::string> Names() const;
  // Which of the free ones is an offset (a translation: normalized by s, metres in SI).
  std::vector<bool> Offsets() const;
  // (sigma, omega) in SI [1, m] from the free values `theta_hat` (omega normalized by `scale`);
  // the fixed one is 0.
  Eigen::Vector2d Values(std::span<const double> theta_hat, double scale) const;
  // d p_c / d (free values), columns 0 .. Count() - 1, of a point p_c corrected at `values`
  // (sigma, omega), omega in the units of p_c (normalized points: Values(theta_hat, 1)).
  Eigen::Matrix<double, 3, 2> PointDerivative(const Eigen::Vector3d& p_c,
                                              const Eigen::Vector2d& values) const;
};

// Re-corrects every point of `dataset` (corrected at `from` (sigma, omega) in SI, raw = 0) to
// `to`: p = p_from (1 + sigma_to) / (1 + sigma_from) + r (omega_to - omega_from (1 + sigma_to) /
// (1 + sigma_from)). Points whose corrected measure would not stay positive become NaN.
void CorrectPoints(MeasureKind measure, const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                   Dataset& dataset);

}  // namespace selfcal::calib
