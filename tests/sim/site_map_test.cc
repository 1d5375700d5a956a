// A site's map from fused points (core/sim/site_map.h): its squares lie on the surface the points
// came from and close it to rays, its occupancy marks where the points are, and stray points
// make neither.
#include "core/sim/site_map.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "core/sim/ray_caster.h"
#include "core/sim/scene.h"

namespace selfcal::sim {
namespace {

// A plane through `origin` with unit `normal`, tilted against every axis of the voxel grid.
struct TiltedPlane {
  Eigen::Vector3d origin{0.3, -0.2, 0.5};
  Eigen::Vector3d normal = Eigen::Vector3d(0.3, 0.2, 0.93).normalized();
  Eigen::Vector3d u = normal.unitOrthogonal();
  Eigen::Vector3d v = normal.cross(u);

  Eigen::Vector3d At(double a, double b) const { return origin + a * u + b * v; }
};

// Points over a 1 m x 1 m patch of the plane, 1 mm of noise along its normal, about 8 per
// 2 cm voxel: what a fused scan of a wall looks like.
std::vector<Eigen::Vector3f> SamplePlane(const TiltedPlane& plane, int count) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> along(-0.5, 0.5);
  std::normal_distribution<double> noise(0.0, 0.001);
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d p = plane.At(along(random), along(random)) + noise(random) * plane.normal;
    points.push_back(p.cast<float>());
  }
  return points;
}

TEST(SiteMap, SquaresLieOnTheSurfaceAndCloseItToRays) {
  const TiltedPlane plane;
  const SiteMap map = BuildSiteMap(SamplePlane(plane, 20000), SiteMapOptions{});
  ASSERT_GT(map.splats, 2000u);  // 2500 voxels of 2 cm on 1 m^2, more where the plane cuts
  EXPECT_EQ(map.points, 20000u);
  ASSERT_EQ(map.surfaces.triangles.size(), 2 * map.splats);
  // Every square is perpendicular to the plane's normal (within 3 degrees) and on it (2 mm).
  for (const Eigen::Vector3i& t : map.surfaces.triangles) {
    const Eigen::Vector3d a = map.surfaces.vertices[static_cast<std::size_t>(t[0])].cast<double>();
    const Eigen::Vector3d b = map.surfaces.vertices[static_cast<std::size_t>(t[1])].cast<double>();
    const Eigen::Vector3d c = map.surfaces.vertices[static_cast<std::size_t>(t[2])].cast<double>();
    const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
    ASSERT_GT(std::abs(n.dot(plane.normal)), std::cos(3.0 * M_PI / 180)) << n.transpose();
    ASSERT_LT(std::abs(((a + b + c) / 3 - plane.origin).dot(plane.normal)), 0.002);
  }
  // Rays along the normal inside the patch all hit, at the plane (no gaps between squares).
  Scene scene;
  UseSiteMap(map, scene);
  auto caster = RayCaster::Create(scene);
  ASSERT_TRUE(caster) << caster.error().message;
  std::mt19937 random(3);
  std::uniform_real_distribution<double> inside(-0.45, 0.45);
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d target = plane.At(inside(random), inside(random));
    const double distance = (*caster)->Cast(target + plane.normal, -plane.normal, 2.0);
    ASSERT_NEAR(distance, 1.0, 0.003) << "ray " << i << " at " << target.transpose();
  }
  EXPECT_EQ(scene.parts.size(), 1u);
  EXPECT_EQ(scene.parts[0].name, "map");
}

TEST(SiteMap, OccupancyKeepsTheSensorOffTheSurface) {
  const TiltedPlane plane;
  Scene scene;
  UseSiteMap(BuildSiteMap(SamplePlane(plane, 20000), SiteMapOptions{}), scene);
  const Eigen::Vector3d on = plane.At(0.1, 0.2);
  EXPECT_FALSE(scene.IsFree(on, 0.0));
  EXPECT_FALSE(scene.IsFree(on + 0.08 * plane.normal, 0.1));  // within the margin
  EXPECT_TRUE(scene.IsFree(on + 0.25 * plane.normal, 0.1));
  EXPECT_TRUE(scene.IsFree(plane.At(2.0, 0.0), 0.1));  // beyond the patch
}

// Points alone in their voxels (flying pixels, a passer-by's few returns) are no surface.
TEST(SiteMap, StrayPointsMakeNoSurfaceAndOccupyNothing) {
  std::vector<Eigen::Vector3f> stray;
  for (int i = 0; i < 100; ++i) stray.emplace_back(0.3f * static_cast<float>(i), 1.0f, 2.0f);
  stray.emplace_back(std::nanf(""), 0.0f, 0.0f);
  const SiteMap map = BuildSiteMap(stray, SiteMapOptions{});
  EXPECT_EQ(map.points, 100u);
  EXPECT_EQ(map.splats, 0u);
  EXPECT_EQ(map.occupied.size(), 0u);
  EXPECT_FALSE(map.occupied.Near({0.0, 1.0, 2.0}, 0.1));
}

}  // namespace
}  // namespace selfcal::sim
