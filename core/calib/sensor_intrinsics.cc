#include "core/calib/sensor_intrinsics.h"

#include <limits>
#include <optional>

namespace selfcal::calib {

namespace {

double MeasureOf(MeasureKind measure, const Eigen::Vector3d& p) {
  return measure == MeasureKind::kRange ? p.norm() : p.z();
}

// p_c of the raw point p.
Eigen::Vector3d Corrected(MeasureKind measure, const Eigen::Vector3d& p, const IntrinsicValues& v) {
  Eigen::Vector3d p_c = p * (1.0 + v[0] + v[1] / MeasureOf(measure, p));
  p_c.head<2>() += v[2] * p.head<2>();
  return p_c;
}

// The raw point of p_c, or nothing when a measure would not be positive. The corrected measure
// is (1 + sigma) m + omega (lambda moves no depth; a LiDAR has none), so m is known first, then
// the point along its ray.
std::optional<Eigen::Vector3d> Raw(MeasureKind measure, const Eigen::Vector3d& p_c,
                                   const IntrinsicValues& v) {
  const double m_c = MeasureOf(measure, p_c);
  const double m = (m_c - v[1]) / (1.0 + v[0]);
  if (!(m_c > 0) || !(m > 0)) return std::nullopt;
  const double along = 1.0 + v[0] + v[1] / m;  // p_c = along p + lambda (x, y, 0)
  Eigen::Vector3d p = p_c / along;
  p.head<2>() = p_c.head<2>() / (along + v[2]);
  return p;
}

}  // namespace

MeasureKind MeasureKindOf(PoseLayout layout) {
  return layout == PoseLayout::kOnePerPoint ? MeasureKind::kRange : MeasureKind::kDepth;
}

HeldIntrinsics HeldIntrinsicsFor(MeasureKind measure, const IntrinsicValues& sd,
                                 const SensorIntrinsics& free) {
  HeldIntrinsics held;
  held.which.measure = measure;
  held.sd = sd;
  held.which.scale = sd[0] > 0 && !free.scale;
  held.which.offset = sd[1] > 0 && !free.offset;
  held.which.focal = sd[2] > 0 && !free.focal && measure == MeasureKind::kDepth;
  return held;
}

std::vector<std::string> SensorIntrinsics::Names() const {
  const std::string prefix = measure == MeasureKind::kRange ? "sensor.range_" : "sensor.depth_";
  std::vector<std::string> names;
  if (scale) names.push_back(prefix + "scale");
  if (offset) names.push_back(prefix + "offset");
  if (focal) names.push_back("sensor.focal_scale");
  return names;
}

std::vector<bool> SensorIntrinsics::Offsets() const {
  std::vector<bool> offsets;
  if (scale) offsets.push_back(false);
  if (offset) offsets.push_back(true);
  if (focal) offsets.push_back(false);
  return offsets;
}

IntrinsicValues SensorIntrinsics::Values(std::span<const double> theta_hat, double scale) const {
  IntrinsicValues values = IntrinsicValues::Zero();
  std::size_t c = 0;
  if (this->scale) values[0] = theta_hat[c++];
  if (offset) values[1] = theta_hat[c++] * scale;
  if (focal) values[2] = theta_hat[c];
  return values;
}

Eigen::Matrix3d SensorIntrinsics::PointDerivative(const Eigen::Vector3d& p_c,
                                                  const IntrinsicValues& values) const {
  Eigen::Matrix3d D = Eigen::Matrix3d::Zero();
  const Eigen::Vector3d p = Raw(measure, p_c, values).value_or(p_c);
  int c = 0;
  if (scale) D.col(c++) = p;
  if (offset) D.col(c++) = p / MeasureOf(measure, p);
  if (focal) D.col(c) << p.x(), p.y(), 0.0;
  return D;
}

void CorrectPoints(MeasureKind measure, const IntrinsicValues& from, const IntrinsicValues& to,
                   Dataset& dataset) {
  if (from == to) return;
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 0; i < dataset.PointCount(); ++i) {
    if (!dataset.IsValid(i)) continue;
    const std::optional<Eigen::Vector3d> p =
        Raw(measure, Eigen::Vector3d(dataset.x[i], dataset.y[i], dataset.z[i]), from);
    const Eigen::Vector3d q = p ? Corrected(measure, *p, to) : Eigen::Vector3d::Zero();
    if (!p || !(MeasureOf(measure, q) > 0)) {
      dataset.x[i] = dataset.y[i] = dataset.z[i] = kNaN;
      continue;
    }
    dataset.x[i] = static_cast<float>(q.x());
    dataset.y[i] = static_cast<float>(q.y());
    dataset.z[i] = static_cast<float>(q.z());
  }
}

}  // namespace selfcal::calib
