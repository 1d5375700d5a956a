#include "core/sim/sensor_model.h"

#include <cmath>
#include <string>

namespace selfcal::sim {

std::vector<Eigen::Vector3d> SensorModel::Rays() const {
  std::vector<Eigen::Vector3d> rays;
  rays.reserve(static_cast<std::size_t>(CellCount()));
  switch (kind) {
    case SensorLayout::kRotatingLidar:
      for (int i = 0; i < width; ++i) {
        const double angle = angle_first + i * angle_increment;
        rays.emplace_back(std::cos(angle), std::sin(angle), 0.0);
      }
      break;
    case SensorLayout::kLineScanner:
      // Points spread evenly in angle over the fan, first point at -x.
      for (int i = 0; i < width; ++i) {
        const double angle = -fan_angle / 2 + fan_angle * (i + 0.5) / width;
        rays.emplace_back(std::tan(angle), 0.0, 1.0);
      }
      break;
    case SensorLayout::kDepthCamera:
      for (int v = 0; v < height; ++v) {
        for (int u = 0; u < width; ++u) rays.push_back(intrinsics.Unproject(u, v, 1.0));
      }
      break;
  }
  return rays;
}

SensorModel SensorModel::Binned(int factor) const {
  SensorModel binned = *this;
  if (kind != SensorLayout::kDepthCamera || factor <= 1) return binned;
  binned.width = width / factor;
  binned.height = height / factor;
  binned.intrinsics = intrinsics.Binned(factor);
  return binned;
}

std::string CheckSensorModel(const SensorModel& model) {
  if (model.width <= 0 || model.height <= 0) return "the sensor grid is empty";
  if (!(model.range_min >= 0 && model.range_max > model.range_min)) return "bad view range";
  if (model.sigma_abs < 0 || model.sigma_rel < 0) return "negative noise";
  switch (model.kind) {
    case SensorLayout::kRotatingLidar:
      if (!(model.time_per_ray > 0 && model.rotation_period > 0)) return "bad LiDAR timing";
      if (model.width * model.time_per_ray > model.rotation_period) {
        return "the LiDAR's rays take longer than one rotation";
      }
      break;
    case SensorLayout::kLineScanner:
      if (!(model.fan_angle > 0 && model.fan_angle < 3.0 && model.line_period > 0)) {
        return "bad line scanner fan angle or line rate";
      }
      break;
    case SensorLayout::kDepthCamera:
      if (!(model.intrinsics.IsValid() && model.frame_period > 0)) {
        return "bad camera intrinsics";
      }
      break;
  }
  return {};
}

}  // namespace selfcal::sim
