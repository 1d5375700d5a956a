// Ray casting against analytic spheres and planes: Embree's answer must equal the closed form
// to float precision.
#include "core/sim/ray_caster.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/sim/random.h"

namespace selfcal::sim {
namespace {

TEST(RayCaster, SpheresMatchTheClosedForm) {
  Scene scene;
  scene.spheres.push_back({Eigen::Vector3d(1.5, 0.2, -0.3), 0.4});
  scene.spheres.push_back({Eigen::Vector3d(-2.0, 1.0, 0.5), 0.75});
  auto caster = RayCaster::Create(scene);
  ASSERT_TRUE(caster.ok()) << caster.error().message;
  Random random(42);
  int hits = 0, misses = 0;
  for (int k = 0; k < 20000; ++k) {
    const Eigen::Vector3d origin(random.Uniform(-0.3, 0.3), random.Uniform(-0.3, 0.3),
                                 random.Uniform(-0.3, 0.3));
    const Eigen::Vector3d direction =
        Eigen::Vector3d(random.Gaussian(), random.Gaussian(), random.Gaussian()).normalized();
    // Closed form: smallest positive t with |o + t d - c| = r.
    double expected = std::numeric_limits<double>::infinity();
    for (const auto& sphere : scene.spheres) {
      const Eigen::Vector3d oc = origin - sphere.center;
      const double b = oc.dot(direction);
      const double c = oc.squaredNorm() - sphere.radius * sphere.radius;
      const double discriminant = b * b - c;
      if (discriminant < 0) continue;
      const double t = -b - std::sqrt(discriminant);
      if (t > 0) expected = std::min(expected, t);
    }
    const double actual = (*caster)->Cast(origin, direction);
    if (std::isinf(expected)) {
      // Grazing rays may go either way in float; require a miss unless it grazes.
      if (!std::isinf(actual)) {
        ADD_FAILURE() << "hit at " << actual << " where the closed form misses";
      }
      ++misses;
    } else {
      ASSERT_FALSE(std::isinf(actual)) << "missed a sphere at " << expected;
      EXPECT_NEAR(actual, expected, 2e-6 * (1 + expected));
      ++hits;
    }
  }
  EXPECT_GT(hits, 500);  // enough rays of each kind to mean something
  EXPECT_GT(misses, 1000);
}

TEST(RayCaster, PlanesMatchTheClosedForm) {
  // A floor at z = -1 and a wall at x = 3, each a finely split quad.
  Scene scene;
  scene.mesh.Append(MakeQuad(Eigen::Vector3d(-10, -10, -1), Eigen::Vector3d(20, 0, 0),
                             Eigen::Vector3d(0, 20, 0), 16));
  scene.mesh.Append(MakeQuad(Eigen::Vector3d(3, -10, -10), Eigen::Vector3d(0, 0, 20),
                             Eigen::Vector3d(0, 20, 0), 16));
  auto caster = RayCaster::Create(scene);
  ASSERT_TRUE(caster.ok()) << caster.error().message;
  Random random(7);
  int checked = 0;
  for (int k = 0; k < 20000; ++k) {
    const Eigen::Vector3d origin(random.Uniform(-0.5, 0.5), random.Uniform(-0.5, 0.5),
                                 random.Uniform(-0.5, 0.5));
    const Eigen::Vector3d direction =
        Eigen::Vector3d(random.Gaussian(), random.Gaussian(), random.Gaussian()).normalized();
    double expected = std::numeric_limits<double>::infinity();
    if (direction.z() < 0) expected = std::min(expected, (-1 - origin.z()) / direction.z());
    if (direction.x() > 0) expected = std::min(expected, (3 - origin.x()) / direction.x());
    const Eigen::Vector3d hit = origin + expected * direction;
    // Only rays whose hit lies well inside the finite quads.
    if (std::isinf(expected) || std::abs(hit.y()) > 9.5 || std::abs(hit.x()) > 9.5 ||
        std::abs(hit.z()) > 9.5)
      continue;
    const double actual = (*caster)->Cast(origin, direction);
    ASSERT_FALSE(std::isinf(actual));
    EXPECT_NEAR(actual, expected, 2e-6 * (1 + expected));
    ++checked;
  }
  EXPECT_GT(checked, 5000);
}

TEST(RayCaster, MaxDistanceAndEmptyDirections) {
  Scene scene;
  scene.spheres.push_back({Eigen::Vector3d(2, 0, 0), 0.5});
  auto caster = RayCaster::Create(scene);
  ASSERT_TRUE(caster.ok());
  EXPECT_NEAR((*caster)->Cast(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX()), 1.5, 1e-6);
  EXPECT_TRUE(std::isinf((*caster)->Cast(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), 1.0)));
  EXPECT_TRUE(std::isinf((*caster)->Cast(Eigen::Vector3d::Zero(), -Eigen::Vector3d::UnitX())));
}

TEST(RayCaster, EmptySceneMissesEverything) {
  auto caster = RayCaster::Create(Scene{});
  ASSERT_TRUE(caster.ok());
  EXPECT_TRUE(std::isinf((*caster)->Cast(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ())));
}

}  // namespace
}  // namespace selfcal::sim
