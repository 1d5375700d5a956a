#include "core/calib/projection.h"

#include <limits>

namespace selfcal::calib {

std::vector<Eigen::Vector3d> BasePoints(const Dataset& dataset, const Chain& chain,
                                        const double* k) {
  std::vector<Eigen::Vector3d> points;
  points.reserve(dataset.ValidPointCount());
  const bool single_pose = dataset.layout == PoseLayout::kOnePerScan;
  double joints[kMaxJoints];
  Transform3<double> pose = chain.Pose(k, dataset.Joints(0, joints));
  for (std::size_t i = 0; i < dataset.PointCount(); ++i) {
    if (!dataset.IsValid(i)) continue;
    if (!single_pose) pose = chain.Pose(k, dataset.Joints(dataset.PoseOf(i), joints));
    points.push_back(pose * NormalizedSensorPoint(dataset, i, chain.scale));
  }
  return points;
}

ProjectedCloud ProjectDataset(const Dataset& dataset, const Chain& chain, const double* k_hat,
                              const PoseKnots* knots) {
  ProjectedCloud cloud;
  const std::size_t count = dataset.PointCount();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cloud.rows = dataset.rows;
  cloud.cols = dataset.cols;
  cloud.x.assign(count, nan);
  cloud.y.assign(count, nan);
  cloud.z.assign(count, nan);
  cloud.nx.assign(count, nan);
  cloud.ny.assign(count, nan);
  cloud.nz.assign(count, nan);
  cloud.keep.assign(count, 0);
  const std::size_t poses = dataset.PoseCount();
  // Poses first (one FK per pose, or per knot), then points through their pose.
  std::vector<Eigen::Matrix<double, 3, 4>> knot_transforms;
  double joints[kMaxJoints];
  if (knots != nullptr) {
    cloud.knots = knots;
    cloud.knot_origin.reserve(knots->KnotCount());
    for (std::uint32_t pose : knots->knot_pose) {
      knot_transforms.push_back(
          chain.Pose(k_hat, dataset.Joints(pose, joints)).matrix().topRows<3>());
      cloud.knot_origin.push_back(knot_transforms.back().col(3));
    }
  } else {
    cloud.origin.resize(3 * poses);
  }
  auto pose_transform = [&](std::size_t pose) -> Eigen::Matrix<double, 3, 4> {
    if (knots == nullptr)
      return chain.Pose(k_hat, dataset.Joints(pose, joints)).matrix().topRows<3>();
    const std::uint32_t a = knots->segment[pose];
    return Blend(knot_transforms[a], knot_transforms[knots->SecondKnot(a)], knots->alpha[pose]);
  };
  std::vector<Eigen::Matrix<double, 3, 4>> transforms(
      dataset.layout == PoseLayout::kOnePerPoint ? 0 : poses);
  for (std::size_t pose = 0; pose < poses; ++pose) {
    const Eigen::Matrix<double, 3, 4> T = pose_transform(pose);
    if (!transforms.empty()) transforms[pose] = T;
    if (knots == nullptr) {
      cloud.origin[3 * pose + 0] = static_cast<float>(T(0, 3));
      cloud.origin[3 * pose + 1] = static_cast<float>(T(1, 3));
      cloud.origin[3 * pose + 2] = static_cast<float>(T(2, 3));
    }
    if (dataset.layout == PoseLayout::kOnePerPoint && dataset.IsValid(pose)) {
      const Eigen::Vector3d p =
          T.leftCols<3>() * NormalizedSensorPoint(dataset, pose, chain.scale) + T.col(3);
      cloud.x[pose] = static_cast<float>(p.x());
      cloud.y[pose] = static_cast<float>(p.y());
      cloud.z[pose] = static_cast<float>(p.z());
    }
  }
  if (dataset.layout == PoseLayout::kOnePerPoint) return cloud;
  for (std::size_t i = 0; i < count; ++i) {
    if (!dataset.IsValid(i)) continue;
    const Eigen::Matrix<double, 3, 4>& T = transforms[dataset.PoseOf(i)];
    const Eigen::Vector3d p =
        T.leftCols<3>() * NormalizedSensorPoint(dataset, i, chain.scale) + T.col(3);
    cloud.x[i] = static_cast<float>(p.x());
    cloud.y[i] = static_cast<float>(p.y());
    cloud.z[i] = static_cast<float>(p.z());
  }
  return cloud;
}

}  // namespace selfcal::calib
