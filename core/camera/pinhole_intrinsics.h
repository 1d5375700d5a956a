// The pinhole camera model every depth camera, simulator and test in selfcal shares (camera frame:
// x right, y down, z forward; pixel (u, v) = (column, row), pixel centres at integer coordinates).
#pragma once

#include <Eigen/Core>

namespace selfcal {

struct PinholeIntrinsics {
  double fx = 0, fy = 0;  // focal lengths [px]
  double cx = 0, cy = 0;  // principal point [px]

  // The point at depth `z` (along the optical axis, not along the ray) seen at pixel (u, v);
  // z = 1 gives the pixel's ray scaled to unit depth.
  Eigen::Vector3d Unproject(double u, double v, double z) const {
    return {z * (u - cx) / fx, z * (v - cy) / fy, z};
  }
  // The pixel (u, v) at which `p_camera` (z > 0) is seen.
  Eigen::Vector2d Project(const Eigen::Vector3d& p_camera) const {
    return {fx * p_camera.x() / p_camera.z() + cx, fy * p_camera.y() / p_camera.z() + cy};
  }

  // Both focal lengths positive and finite.
  bool IsValid() const;

  // The same field of view at a resolution reduced by an integer factor (binning): a binned
  // pixel covers factor x factor original pixels. Factors below 2 return the intrinsics unchanged.
  PinholeIntrinsics Binned(int factor) const;

  // The pinhole model of a field of view: f = (size / 2) / tan(fov / 2), centre at
  // (size - 1) / 2. Angles in rad, full opening angles.
  static PinholeIntrinsics FromFieldOfView(int width, int height, double horizontal_fov,
                                           double vertical_fov);
};

}  // namespace selfcal
