#include "core/calib/held_out_registration.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <memory>

#include "core/calib/matching.h"
#include "core/calib/parallel.h"
#include "core/util/release.h"

namespace selfcal::calib {
namespace {

// Enough points to average the noise of a scan far below the offsets that matter, few enough
// that registering every held-out scan costs less than one ICP iteration.
constexpr std::size_t kMaxQueries = 20000;
constexpr std::size_t kMinMatches = 100;
constexpr int kMaxSteps = 30;
constexpr double kMinStep = 1e-7;  // normalized units (about 0.1 um for a 1 m scene)

// The reference: the fit scans' filtered points with normals, concatenated (every stride-th,
// at most about kMaxMapPoints: a LiDAR's tens of millions would cost a gigabyte here), and a tree
// over them.
constexpr std::size_t kMaxMapPoints = 4000000;

struct FitMap {
  std::vector<float> x, y, z, nx, ny, nz;
  std::vector<std::uint8_t> border;  // 1 = on the border of its scan's coverage
  std::unique_ptr<PointTree> tree;

  Eigen::Vector3d Point(std::size_t i) const { return {x[i], y[i], z[i]}; }
  Eigen::Vector3d Normal(std::size_t i) const { return {nx[i], ny[i], nz[i]}; }
};

bool Usable(const ProjectedCloud& cloud, std::size_t i) {
  return cloud.keep[i] && cloud.HasNormal(i);
}

// Frees each fit scan's cloud once its points are in the map: the map's points would otherwise
// come on top of every cloud (a depth camera's 26 bytes a point).
FitMap BuildFitMap(const std::vector<Dataset>& datasets, std::vector<ProjectedCloud>& clouds) {
  std::size_t usable = 0;
  for (std::size_t d = 0; d < datasets.size(); ++d) {
    if (datasets[d].validation) continue;
    for (std::size_t i = 0; i < clouds[d].keep.size(); ++i) usable += Usable(clouds[d], i);
  }
  const std::size_t stride = std::max<std::size_t>(1, (usable + kMaxMapPoints - 1) / kMaxMapPoints);
  FitMap map;
  const std::size_t taken = (usable + stride - 1) / stride;
  for (auto* values : {&map.x, &map.y, &map.z, &map.nx, &map.ny, &map.nz}) values->reserve(taken);
  map.border.reserve(taken);
  std::size_t seen = 0;
  for (std::size_t d = 0; d < datasets.size(); ++d) {
    if (datasets[d].validation) continue;
    const ProjectedCloud& cloud = clouds[d];
    for (std::size_t i = 0; i < cloud.keep.size(); ++i) {
      if (!Usable(cloud, i) || seen++ % stride != 0) continue;
      map.x.push_back(cloud.x[i]);
      map.y.push_back(cloud.y[i]);
      map.z.push_back(cloud.z[i]);
      map.nx.push_back(cloud.nx[i]);
      map.ny.push_back(cloud.ny[i]);
      map.nz.push_back(cloud.nz[i]);
      map.border.push_back(cloud.boundary.empty() ? 0 : cloud.boundary[i]);
    }
    clouds[d] = ProjectedCloud();
  }
  ReturnFreedMemory();
  map.tree =
      std::make_unique<PointTree>(map.x, map.y, map.z, std::vector<std::uint8_t>(map.x.size(), 1));
  return map;
}

// Every stride-th point of the scan's filter result that has a normal, at most kMaxQueries.
std::vector<std::uint32_t> QueryPoints(const ProjectedCloud& cloud) {
  std::vector<std::uint32_t> usable;
  for (std::size_t i = 0; i < cloud.keep.size(); ++i)
    if (Usable(cloud, i)) usable.push_back(static_cast<std::uint32_t>(i));
  const std::size_t stride =
      std::max<std::size_t>(1, (usable.size() + kMaxQueries - 1) / kMaxQueries);
  std::vector<std::uint32_t> queries;
  for (std::size_t i = 0; i < usable.size(); i += stride) queries.push_back(usable[i]);
  return queries;
}

Eigen::Vector3d MeanOrigin(const ProjectedCloud& cloud) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  const std::size_t poses = cloud.PoseCount();
  for (std::size_t p = 0; p < poses; ++p) sum += cloud.Origin(p).cast<double>();
  return poses > 0 ? Eigen::Vector3d(sum / static_cast<double>(poses)) : sum;
}

struct MatchLimits {
  double d_max = 0;  // normalized units
  double f_min = 0;  // cosine
  bool reject_border = false;
};

// A rigid motion x -> rotation (x - centre) + centre + translation.
struct RigidMotion {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();

  Eigen::Vector3d Apply(const Eigen::Vector3d& x) const {
    return rotation * (x - centre) + centre + translation;
  }
};

struct Step {
  Eigen::Matrix<double, 6, 1> delta = Eigen::Matrix<double, 6, 1>::Zero();  // rotation, shift
  std::size_t matches = 0;
};

// One Gauss-Newton step of the point-to-plane cost of the moved queries against their nearest
// map points: r = (x' - q) . n(q), dr/d(omega, tau) = ((x' - c') x n, n).
Step GaussNewtonStep(const ProjectedCloud& cloud, const std::vector<std::uint32_t>& queries,
                     const FitMap& map, const RigidMotion& motion, const MatchLimits& limits) {
  const float d_max = static_cast<float>(limits.d_max);
  const Eigen::Vector3d moved_centre = motion.centre + motion.translation;
  Eigen::Matrix<double, 6, 6> hessian = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> gradient = Eigen::Matrix<double, 6, 1>::Zero();
  Step step;
  std::uint32_t hint = 0;
  for (std::uint32_t i : queries) {
    const Eigen::Vector3d x = motion.Apply(cloud.Point(i).cast<double>());
    float distance_squared = 0;
    const long nearest = map.tree->Nearest(x.cast<float>(), d_max, distance_squared, &hint);
    if (nearest < 0) continue;
    const auto j = static_cast<std::size_t>(nearest);
    if (limits.reject_border && map.border[j]) continue;
    const Eigen::Vector3d n = map.Normal(j);
    if ((motion.rotation * cloud.Normal(i).cast<double>()).dot(n) < limits.f_min) continue;
    Eigen::Matrix<double, 6, 1> jacobian;
    jacobian << (x - moved_centre).cross(n), n;
    const double r = (x - map.Point(j)).dot(n);
    hessian += jacobian * jacobian.transpose();
    gradient += jacobian * r;
    ++step.matches;
  }
  if (step.matches < kMinMatches) return step;
  hessian.diagonal().array() += 1e-9 * hessian.trace();
  step.delta = -hessian.ldlt().solve(gradient);
  return step;
}

HeldOutOffset RegisterScan(const Dataset& dataset, const ProjectedCloud& cloud, const FitMap& map,
                           const MatchLimits& limits, double scale) {
  HeldOutOffset offset;
  offset.scan_index = dataset.scan_index;
  const std::vector<std::uint32_t> queries = QueryPoints(cloud);
  RigidMotion motion;
  for (std::uint32_t i : queries) motion.centre += cloud.Point(i).cast<double>();
  if (!queries.empty()) motion.centre /= static_cast<double>(queries.size());
  for (int s = 0; s < kMaxSteps; ++s) {
    const Step step = GaussNewtonStep(cloud, queries, map, motion, limits);
    offset.matches = step.matches;
    if (step.matches < kMinMatches) return offset;
    const Eigen::Vector3d omega = step.delta.head<3>();
    const double angle = omega.norm();
    if (angle > 0) motion.rotation = Eigen::AngleAxisd(angle, omega / angle) * motion.rotation;
    motion.translation += step.delta.tail<3>();
    if (step.delta.norm() < kMinStep) break;
  }
  const Eigen::Vector3d origin = MeanOrigin(cloud);
  offset.position_m = (motion.Apply(origin) - origin).norm() * scale;
  offset.angle_rad = Eigen::AngleAxisd(motion.rotation).angle();
  return offset;
}

}  // namespace

HeldOutRegistration RegisterHeldOutScans(const std::vector<Dataset>& datasets,
                                         std::vector<ProjectedCloud>&& clouds, double d_max_m,
                                         double f_min, bool reject_border, double scale,
                                         int threads) {
  HeldOutRegistration registration;
  std::vector<std::size_t> held_out;
  for (std::size_t d = 0; d < datasets.size(); ++d)
    if (datasets[d].validation) held_out.push_back(d);
  if (held_out.empty()) return registration;
  const FitMap map = BuildFitMap(datasets, clouds);
  if (map.x.empty()) return registration;
  const MatchLimits limits{d_max_m / scale, f_min, reject_border};
  std::vector<HeldOutOffset> offsets(held_out.size());
  ParallelFor(held_out.size(), threads, [&](std::size_t v) {
    offsets[v] = RegisterScan(datasets[held_out[v]], clouds[held_out[v]], map, limits, scale);
  });
  double squared = 0;
  for (const HeldOutOffset& offset : offsets) {
    if (offset.matches < kMinMatches) continue;
    registration.scans.push_back(offset);
    squared += offset.position_m * offset.position_m;
    registration.worst_position_m = std::max(registration.worst_position_m, offset.position_m);
  }
  if (!registration.scans.empty())
    registration.rms_position_m =
        std::sqrt(squared / static_cast<double>(registration.scans.size()));
  return registration;
}

}  // namespace selfcal::calib
