// The analytic depth scene our simulated cameras serve (the fake GigE Vision camera and the
// OpenNI2 driver plugin): a tilted wall with a ball in front of it, seen by a pinhole camera.
// Analytic so that tests can compute the truth independently; core/sim's ray-cast scenes can
// replace it behind the same DepthAt call.
#pragma once

#include <cstdint>

#include "core/camera/pinhole_intrinsics.h"

namespace selfcal::sim_cameras {

struct AnalyticDepthScene {
  // Wall: the plane through (0, 0, wall_distance) with normal (0, wall_slope, -1) (camera frame:
  // x right, y down, z forward), so the wall recedes towards the bottom of the image.
  double wall_distance_m = 0.85;
  double wall_slope = 0.5;
  // Ball.
  double ball_x_m = 0.05, ball_y_m = -0.03, ball_z_m = 0.62, ball_radius_m = 0.08;
  // Measurements outside [closest, farthest] are invalid (PhotoNeo M: 0.497 .. 0.939 m).
  double closest_m = 0.497, farthest_m = 0.939;

  // Depth z [m] of the first surface on the ray through pixel (u, v); 0 when the point is outside
  // the view range.
  double DepthAt(double u, double v, const PinholeIntrinsics& intrinsics) const;
};

// Deterministic Gaussian noise (per frame and pixel), so that runs repeat exactly.
double GaussianNoise(std::uint64_t frame, std::uint64_t pixel);

}  // namespace selfcal::sim_cameras
