#include "tools/sim_cameras/depth_scene.h"

#include <cmath>

namespace selfcal::sim_cameras {

double AnalyticDepthScene::DepthAt(double u, double v, const PinholeIntrinsics& k) const {
  // Ray p = t * (a, b, 1): t is the depth z of the hit.
  const Eigen::Vector3d ray = k.Unproject(u, v, 1.0);
  const double a = ray.x();
  const double b = ray.y();
  double depth = 0.0;
  // Ball: |t r - c|^2 = R^2, nearest root.
  const double rr = a * a + b * b + 1.0;
  const double rc = a * ball_x_m + b * ball_y_m + ball_z_m;
  const double cc = ball_x_m * ball_x_m + ball_y_m * ball_y_m + ball_z_m * ball_z_m;
  const double discriminant = rc * rc - rr * (cc - ball_radius_m * ball_radius_m);
  if (discriminant >= 0.0) depth = (rc - std::sqrt(discriminant)) / rr;
  if (depth <= 0.0) {
    // Wall: n . (t r - p0) = 0 with n = (0, s, -1), p0 = (0, 0, d): t = d / (1 - s b).
    const double denominator = 1.0 - wall_slope * b;
    depth = denominator > 0.0 ? wall_distance_m / denominator : 0.0;
  }
  return (depth >= closest_m && depth <= farthest_m) ? depth : 0.0;
}

double GaussianNoise(std::uint64_t frame, std::uint64_t pixel) {
  // SplitMix64 of (frame, pixel), two uniforms, Box-Muller.
  const auto mix = [](std::uint64_t z) {
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  };
  const std::uint64_t h1 = mix(frame * 0x100000001B3ull ^ pixel);
  const std::uint64_t h2 = mix(h1);
  const double u1 = (static_cast<double>(h1 >> 11) + 1.0) / 9007199254740993.0;
  const double u2 = static_cast<double>(h2 >> 11) / 9007199254740992.0;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
}

}  // namespace selfcal::sim_cameras
