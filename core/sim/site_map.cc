#include "core/sim/site_map.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <unordered_map>
#include <utility>

namespace selfcal::sim {
namespace {

// The points of one voxel, as sums for their mean and covariance.
struct Moments {
  int count = 0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();

  void Add(const Eigen::Vector3d& p) {
    ++count;
    sum += p;
    outer += p * p.transpose();
  }
};

using VoxelMoments = std::unordered_map<std::uint64_t, Moments>;

// The least-variance direction of the points in the 3 x 3 x 3 voxels around `centre`: a voxel
// that the surface only clips holds a few points in a sliver, whose own spread says little.
Eigen::Vector3d NormalAround(const VoxelMoments& voxels, const Eigen::Vector3d& centre,
                             double voxel_m) {
  Moments around;
  for (int x = -1; x <= 1; ++x) {
    for (int y = -1; y <= 1; ++y) {
      for (int z = -1; z <= 1; ++z) {
        const auto found =
            voxels.find(VoxelKey(centre + voxel_m * Eigen::Vector3d(x, y, z), voxel_m));
        if (found == voxels.end()) continue;
        around.count += found->second.count;
        around.sum += found->second.sum;
        around.outer += found->second.outer;
      }
    }
  }
  const Eigen::Vector3d mean = around.sum / around.count;
  const Eigen::Matrix3d covariance = around.outer / around.count - mean * mean.transpose();
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance).eigenvectors().col(0);
}

// A square of half-width `half` through `centre`, perpendicular to `normal`.
TriangleMesh Splat(const Eigen::Vector3d& centre, const Eigen::Vector3d& normal, double half) {
  const Eigen::Vector3d u = normal.unitOrthogonal();
  const Eigen::Vector3d v = normal.cross(u);
  return MakeQuad(centre - half * (u + v), 2 * half * u, 2 * half * v);
}

}  // namespace

SiteMap BuildSiteMap(std::span<const Eigen::Vector3f> points, const SiteMapOptions& options) {
  SiteMap map;
  map.occupied = Occupancy(options.occupancy_voxel_m);
  VoxelMoments voxels;
  std::unordered_map<std::uint64_t, int> occupancy_counts;
  for (const Eigen::Vector3f& p : points) {
    if (!p.allFinite()) continue;
    const Eigen::Vector3d point = p.cast<double>();
    ++map.points;
    voxels[VoxelKey(point, options.surface_voxel_m)].Add(point);
    if (++occupancy_counts[VoxelKey(point, options.occupancy_voxel_m)] == options.min_points)
      map.occupied.Mark(point);
  }
  // Squares twice the voxel's width: a voxel the surface only clips may hold too few points to
  // count, and its neighbours' squares must cover it. Surfaces grow by up to a voxel at their
  // edges, which planning can afford.
  const double half = options.surface_voxel_m;
  for (const auto& [key, moments] : voxels) {
    if (moments.count < options.min_points) continue;
    const Eigen::Vector3d mean = moments.sum / moments.count;
    map.surfaces.Append(Splat(mean, NormalAround(voxels, mean, options.surface_voxel_m), half));
    ++map.splats;
  }
  return map;
}

void UseSiteMap(SiteMap map, Scene& scene) {
  scene.mesh = std::move(map.surfaces);
  scene.spheres.clear();
  scene.albedo.clear();
  scene.parts = {{"map", 0, scene.mesh.triangles.size()}};
  scene.occupied = std::move(map.occupied);
}

}  // namespace selfcal::sim
