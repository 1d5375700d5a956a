// Sensor models of the paper's Table I, in the sensor's own frame (frames as in the .lcm files:
// LiDAR rays in the xy plane, angle from +x towards +y; line scanner points in the xz plane, z
// along the optical axis; cameras x right, y down, z forward).
//
// Core owns no file formats: protocols/scenario fills this from a SensorConfig.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/camera/pinhole_intrinsics.h"
#include "core/model/sensor_layout.h"

namespace selfcal::sim {

struct SensorModel {
  SensorLayout kind = SensorLayout::kDepthCamera;
  // Grid: LiDAR `width` rays per rotation; line scanner `width` points per line; camera width x
  // height pixels. `height` is 1 for LiDAR and line scanner.
  int width = 0;
  int height = 1;
  // View range [m]: along the ray for the LiDAR, along z for the line scanner and cameras.
  double range_min = 0;
  double range_max = 0;
  // Gaussian noise, sigma = sigma_abs + sigma_rel * range (range as above), applied to that
  // same measure: LiDAR range, line scanner and camera depth z.
  double sigma_abs = 0;
  double sigma_rel = 0;

  // Rotating LiDAR.
  double angle_first = 0;      // rad
  double angle_increment = 0;  // rad
  double time_per_ray = 0;     // s
  double rotation_period = 0;  // s
  // Line scanner.
  double fan_angle = 0;    // rad
  double line_period = 0;  // s
  // Depth camera.
  PinholeIntrinsics intrinsics;
  double frame_period = 0;  // s

  int CellCount() const { return width * height; }

  // One ray per grid cell, row-major (camera row v, column u at index v * width + u). Unit
  // vectors for the LiDAR; for the line scanner and cameras scaled to z = 1, so that a depth z
  // gives the point z * ray.
  std::vector<Eigen::Vector3d> Rays() const;

  // Standard deviation of the noise at `range` (the measure above).
  double Sigma(double range) const { return sigma_abs + sigma_rel * range; }

  // Reduces a camera's resolution by an integer factor (binning), keeping its field of view.
  SensorModel Binned(int factor) const;
};

// Empty string when the model is usable, otherwise what is wrong.
std::string CheckSensorModel(const SensorModel& model);

}  // namespace selfcal::sim
