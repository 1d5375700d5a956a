#include "core/calib/normals.h"

namespace selfcal::calib {

namespace {

// m(a, b): unit cross product, or zero when degenerate.
Eigen::Vector3f UnitCross(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  const Eigen::Vector3f c = a.cross(b);
  const float norm = c.norm();
  if (!(norm > 1e-12f)) return Eigen::Vector3f::Zero();
  return c / norm;
}

}  // namespace

void ComputeNormals(const Dataset& dataset, ProjectedCloud& cloud) {
  const std::size_t rows = cloud.rows;
  const std::size_t cols = cloud.cols;
  auto valid = [&](std::size_t r, std::size_t c) { return cloud.Valid(r * cols + c); };
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < cols; ++c) {
      const std::size_t i = r * cols + c;
      if (!cloud.Valid(i)) continue;
      const Eigen::Vector3f p = cloud.Point(i);
      Eigen::Vector3f sum = Eigen::Vector3f::Zero();
      if (r > 0 && c > 0 && valid(r - 1, c) && valid(r, c - 1)) {
        sum += UnitCross(cloud.Point(i - cols) - p, cloud.Point(i - 1) - p);
      }
      if (r + 1 < rows && c + 1 < cols && valid(r + 1, c) && valid(r, c + 1)) {
        sum += UnitCross(cloud.Point(i + cols) - p, cloud.Point(i + 1) - p);
      }
      const float norm = sum.norm();
      if (!(norm > 1e-6f)) continue;
      Eigen::Vector3f n = sum / norm;
      const std::size_t pose = dataset.PoseOf(i);
      const Eigen::Vector3f origin(cloud.origin[3 * pose], cloud.origin[3 * pose + 1],
                                   cloud.origin[3 * pose + 2]);
      if (n.dot(p - origin) > 0.0f) n = -n;
      cloud.nx[i] = n.x();
      cloud.ny[i] = n.y();
      cloud.nz[i] = n.z();
    }
  }
}

}  // namespace selfcal::calib
