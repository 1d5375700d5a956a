#include "core/calib/sensor_intrinsics.h"

#include <limits>

namespace selfcal::calib {

namespace {

double MeasureOf(MeasureKind measure, const Eigen::Vector3d& p) {
  return measure == MeasureKind::kRange ? p.norm() : p.z();
}

}  // namespace

MeasureKind MeasureKindOf(PoseLayout layout) {
  return layout == PoseLayout::kOnePerPoint ? MeasureKind::kRange : MeasureKind::kDepth;
}

std::vector<std::string> SensorIntrinsics::Names() const {
  const std::string prefix = measure == MeasureKind::kRange ? "sensor.range_" : "sensor.depth_";
  std::vector<std::string> names;
  if (scale) names.push_back(prefix + "scale");
  if (offset) names.push_back(prefix + "offset");
  return names;
}

std::vector<bool> SensorIntrinsics::Offsets() const {
  std::vector<bool> offsets;
  if (scale) offsets.push_back(false);
  if (offset) offsets.push_back(true);
  return offsets;
}

Eigen::Vector2d SensorIntrinsics::Values(std::span<const double> theta_hat, double scale) const {
  Eigen::Vector2d values = Eigen::Vector2d::Zero();
  std::size_t c = 0;
  if (this->scale) values[0] = theta_hat[c++];
  if (offset) values[1] = theta_hat[c] * scale;
  return values;
}

Eigen::Matrix<double, 3, 2> SensorIntrinsics::PointDerivative(const Eigen::Vector3d& p_c,
                                                              const Eigen::Vector2d& values) const {
  Eigen::Matrix<double, 3, 2> D = Eigen::Matrix<double, 3, 2>::Zero();
  const Eigen::Vector3d ray = p_c / MeasureOf(measure, p_c);
  int c = 0;
  if (scale) D.col(c++) = (p_c - values[1] * ray) / (1.0 + values[0]);  // the raw point
  if (offset) D.col(c) = ray;
  return D;
}

void CorrectPoints(MeasureKind measure, const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                   Dataset& dataset) {
  if (from == to) return;
  const double ratio = (1.0 + to[0]) / (1.0 + from[0]);
  const double shift = to[1] - from[1] * ratio;
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 0; i < dataset.PointCount(); ++i) {
    if (!dataset.IsValid(i)) continue;
    const Eigen::Vector3d p(dataset.x[i], dataset.y[i], dataset.z[i]);
    const double m = MeasureOf(measure, p);
    const double corrected = m * ratio + shift;
    if (!(m > 0) || !(corrected > 0)) {
      dataset.x[i] = dataset.y[i] = dataset.z[i] = kNaN;
      continue;
    }
    const Eigen::Vector3d q = p * (corrected / m);
    dataset.x[i] = static_cast<float>(q.x());
    dataset.y[i] = static_cast<float>(q.y());
    dataset.z[i] = static_cast<float>(q.z());
  }
}

}  // namespace selfcal::calib
