// The sensor's intrinsics calibrated with the arm (docs/engine.md, deviation 17): what real
// units get wrong about their points, a scale and an offset of the measure along each ray (a
// time-of-flight camera's depth scale and offset, a LiDAR's range offset, a line scanner's depth
// scale) and a camera's focal length (its lateral scale). The engine corrects every recorded
// point p = (x, y, z),
//   p_c = (1 + sigma) p + omega p / m(p) + lambda (x, y, 0),
// m(p) the measure of the point: its depth z for depth cameras and line scanners (their rays have
// z = 1), its range |p| for a rotating LiDAR (unit rays; no lambda). So the corrected measure is
// (1 + sigma) m + omega along the ray, and a camera's rays spread by (1 + lambda) sideways: a
// focal length (1 + lambda) times too long. Linear in theta = (sigma, omega, lambda):
// d p_c / d theta = (p, p / m(p), (x, y, 0)). A sensor whose true measure is m_true reads
// (1 + s) m_true + o has sigma = 1 / (1 + s) - 1 and omega = -o / (1 + s).
//
// In k_hat the free ones follow every other parameter (chain.h), in the order scale, offset,
// focal: omega divided by the normalization scale like every translation. The engine keeps the
// datasets' points corrected at the current estimate (CorrectPoints, once per ICP iteration
// with the joint correction's freeze), so projection, normals, matching and the cost read
// corrected points as they read raw ones; only the cost's derivative needs PointDerivative.
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

using IntrinsicValues = Eigen::Vector3d;  // (sigma, omega, lambda); the fixed ones are 0

struct SensorIntrinsics {
  bool scale = false;   // sigma free
  bool offset = false;  // omega free
  bool focal = false;   // lambda free (depth measures only)
  MeasureKind measure = MeasureKind::kDepth;

  std::size_t Count() const { return (scale ? 1 : 0) + (offset ? 1 : 0) + (focal ? 1 : 0); }
  bool Empty() const { return Count() == 0; }
  // "sensor.depth_scale", "sensor.depth_offset", "sensor.focal_scale" (a LiDAR: range_), in
  // k_hat's order.
  std::vector<std::string> Names() const;
  // Which of the free ones is an offset (a translation: normalized by s, metres in SI).
  std::vector<bool> Offsets() const;
  // (sigma, omega, lambda) from the free values `theta_hat`, omega times `scale` (the
  // normalization scale for SI, 1 for normalized units).
  IntrinsicValues Values(std::span<const double> theta_hat, double scale) const;
  // d p_c / d (free values), columns 0 .. Count() - 1, of a point p_c corrected at `values`,
  // omega in the units of p_c (normalized points: Values(theta_hat, 1)).
  Eigen::Matrix3d PointDerivative(const Eigen::Vector3d& p_c, const IntrinsicValues& values) const;
};

// The intrinsics a calibration holds at the sensor file's values although they are uncertain, and
// their uncertainty (1 sigma, a datasheet's or a site's): sigma, omega [m] and lambda as above.
// The consider covariance (covariance.h) adds what that uncertainty does to the estimate.
struct HeldIntrinsics {
  SensorIntrinsics which;  // the held ones: none of them free
  IntrinsicValues sd = IntrinsicValues::Zero();
  bool Empty() const { return which.Empty(); }
};

// What a calibration holds with `sd` (as HeldIntrinsics::sd) whose free intrinsics are `free`:
// each with an uncertainty that is not free (a range measure has no focal length).
HeldIntrinsics HeldIntrinsicsFor(MeasureKind measure, const IntrinsicValues& sd,
                                 const SensorIntrinsics& free);

// Re-corrects every point of `dataset` (corrected at `from`, raw = 0; omega in m) to `to`.
// Points whose raw or corrected measure would not be positive become NaN.
void CorrectPoints(MeasureKind measure, const IntrinsicValues& from, const IntrinsicValues& to,
                   Dataset& dataset);

}  // namespace selfcal::calib
