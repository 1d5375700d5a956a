#include "protocols/scenario/sensor_model_config.h"

namespace selfcal {

sim::SensorModel ToSensorModel(const SensorConfig& config, int camera_binning) {
  sim::SensorModel model;
  model.range_min = config.range_closest;
  model.range_max = config.range_farthest;
  model.sigma_abs = config.sigma_abs;
  model.sigma_rel = config.sigma_rel;
  model.kind = config.layout;
  switch (config.layout) {
    case SensorLayout::kRotatingLidar:
      model.width = config.lidar.steps;
      model.height = 1;
      model.angle_first = config.lidar.angle_first;
      model.angle_increment = config.lidar.angle_increment;
      model.rotation_period = 1.0 / config.lidar.rotation_rate_hz;
      model.time_per_ray = model.rotation_period / config.lidar.steps_per_rotation;
      break;
    case SensorLayout::kLineScanner:
      model.width = config.line.points;
      model.height = 1;
      model.fan_angle = config.line.fan_angle;
      model.line_period = 1.0 / config.line.line_rate_hz;
      break;
    case SensorLayout::kDepthCamera:
      model.width = config.resolution_x;
      model.height = config.resolution_y;
      model.intrinsics = config.camera.intrinsics;
      model.frame_period = 1.0 / config.camera.frame_rate_hz;
      model = model.Binned(camera_binning);
      break;
  }
  return model;
}

std::string CheckCameraBinning(const SensorConfig& config, int camera_binning) {
  if (config.layout != SensorLayout::kDepthCamera) return "";
  if (config.resolution_x >= camera_binning && config.resolution_y >= camera_binning) return "";
  return std::to_string(camera_binning) + " leaves no pixel of the " +
         std::to_string(config.resolution_x) + "x" + std::to_string(config.resolution_y) +
         " sensor";
}

}  // namespace selfcal
