#include "core/calib/flying_pixels.h"

#include <Eigen/Core>
#include <cmath>

namespace selfcal::calib {

namespace {

Eigen::Vector3d PointAt(const Dataset& dataset, std::size_t i) {
  return {dataset.x[i], dataset.y[i], dataset.z[i]};
}

// True when p and q, seen from the sensor's origin, differ along the view ray by more than both
// the angle and the noise allow.
bool IsJump(const Eigen::Vector3d& p, const Eigen::Vector3d& q, double cot_min_angle,
            const FlyingPixelRule& rule) {
  const Eigen::Vector3d mid = 0.5 * (p + q);
  const double range = mid.norm();
  if (!(range > 0)) return false;
  const Eigen::Vector3d ray = mid / range;
  const Eigen::Vector3d d = q - p;
  const double along = std::abs(d.dot(ray));
  const double lateral = (d - d.dot(ray) * ray).norm();
  const double noise = rule.sigmas * std::sqrt(2.0) * (rule.sigma_abs + rule.sigma_rel * range);
  return along > noise && along > lateral * cot_min_angle;
}

}  // namespace

std::vector<std::uint8_t> FlyingPixels(const Dataset& dataset, const FlyingPixelRule& rule) {
  if (!(rule.min_angle_rad > 0)) return {};
  const double cot_min_angle = 1.0 / std::tan(rule.min_angle_rad);
  // Neighbours measured at the same instant: along rows always (the next row of a column), along
  // columns only where the whole grid is one instant (a depth image).
  const bool across_columns = dataset.layout == PoseLayout::kOnePerScan;
  std::vector<std::uint8_t> flying(dataset.PointCount(), 0);
  const auto test = [&](std::size_t i, std::size_t k) {
    if (!dataset.IsValid(i) || !dataset.IsValid(k)) return;
    if (IsJump(PointAt(dataset, i), PointAt(dataset, k), cot_min_angle, rule))
      flying[i] = flying[k] = 1;
  };
  for (std::size_t r = 0; r < dataset.rows; ++r) {
    for (std::size_t c = 0; c < dataset.cols; ++c) {
      const std::size_t i = r * dataset.cols + c;
      if (r + 1 < dataset.rows) test(i, i + dataset.cols);
      if (across_columns && c + 1 < dataset.cols) test(i, i + 1);
    }
  }
  return flying;
}

}  // namespace selfcal::calib
