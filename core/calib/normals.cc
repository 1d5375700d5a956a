#include "core/calib/normals.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace selfcal::calib {

namespace {

// m(a, b): unit cross product, or zero when degenerate.
Eigen::Vector3f UnitCross(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  const Eigen::Vector3f c = a.cross(b);
  const float norm = c.norm();
  if (!(norm > 1e-12f)) return Eigen::Vector3f::Zero();
  return c / norm;
}

void SetOrientedNormal(ProjectedCloud& cloud, std::size_t i, const Eigen::Vector3f& origin,
                       Eigen::Vector3f n) {
  if (n.dot(cloud.Point(i) - origin) > 0.0f) n = -n;
  cloud.nx[i] = n.x();
  cloud.ny[i] = n.y();
  cloud.nz[i] = n.z();
}

// The plane through the valid points of the window (r0..r1) x (c0..c1) fitted along their rays
// from `origin` (see ComputeFittedNormals); zero when fewer than kMinPoints or degenerate.
Eigen::Vector3f FitWindowNormal(const ProjectedCloud& cloud, const Eigen::Vector3f& origin,
                                std::size_t r0, std::size_t r1, std::size_t c0, std::size_t c1) {
  constexpr int kMinPoints = 5;
  Eigen::Matrix3d normal_matrix = Eigen::Matrix3d::Zero();
  Eigen::Vector3d right_side = Eigen::Vector3d::Zero();
  int count = 0;
  const Eigen::Vector3d o = origin.cast<double>();
  for (std::size_t r = r0; r <= r1; ++r) {
    for (std::size_t c = c0; c <= c1; ++c) {
      const std::size_t k = r * cloud.cols + c;
      if (!cloud.Valid(k)) continue;
      const Eigen::Vector3d ray = cloud.Point(k).cast<double>() - o;
      const double t = ray.norm();
      if (!(t > 0)) continue;
      const Eigen::Vector3d d = ray / t;
      normal_matrix.noalias() += d * d.transpose();
      right_side += d / t;
      ++count;
    }
  }
  if (count < kMinPoints) return Eigen::Vector3f::Zero();
  // Rays within the window are nearly parallel: the system is ill-conditioned by nature (its
  // smallest eigenvalue ~ the window's angular extent squared), so solve it by LDLT in double and
  // reject only what spans no plane.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> spread(normal_matrix,
                                                              Eigen::EigenvaluesOnly);
  if (!(spread.eigenvalues()(0) > 1e-12 * spread.eigenvalues()(2))) {
    return Eigen::Vector3f::Zero();
  }
  const Eigen::Vector3d h = normal_matrix.ldlt().solve(right_side);
  const double norm = h.norm();
  if (!(norm > 0) || !std::isfinite(norm)) return Eigen::Vector3f::Zero();
  return (h / norm).cast<float>();
}

}  // namespace

void ComputeFittedNormals(const Dataset& dataset, ProjectedCloud& cloud, int n, int m) {
  const std::size_t rows = cloud.rows;
  const std::size_t cols = cloud.cols;
  const std::size_t dn = static_cast<std::size_t>(n), dm = static_cast<std::size_t>(m);
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < cols; ++c) {
      const std::size_t i = r * cols + c;
      if (!cloud.Valid(i)) continue;
      const Eigen::Vector3f origin = cloud.Origin(dataset.PoseOf(i));
      const Eigen::Vector3f normal =
          FitWindowNormal(cloud, origin, r > dn ? r - dn : 0, std::min(rows - 1, r + dn),
                          c > dm ? c - dm : 0, std::min(cols - 1, c + dm));
      if (normal.isZero()) continue;
      SetOrientedNormal(cloud, i, origin, normal);
    }
  }
}

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
      SetOrientedNormal(cloud, i, cloud.Origin(dataset.PoseOf(i)), sum / norm);
    }
  }
}

}  // namespace selfcal::calib
