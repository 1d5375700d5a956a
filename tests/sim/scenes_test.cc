// Scenes: the bunny from glmark2-data at a real size, Newell's teapot, the procedural rooms.
#include <gtest/gtest.h>

#include <cmath>

#include "core/sim/obj_mesh.h"
#include "core/sim/ray_caster.h"
#include "core/sim/scene.h"
#include "core/sim/teapot.h"

namespace selfcal::sim {
namespace {

constexpr const char* kBunny = "/usr/share/glmark2/models/bunny.obj";

TEST(Scenes, BunnyHasTheRequestedHeightAndStandsOnZero) {
  auto bunny = MakeBunny(kBunny, 0.16);
  ASSERT_TRUE(bunny.ok()) << bunny.error().message;
  EXPECT_EQ(bunny->vertices.size(), 34835u);
  EXPECT_GT(bunny->triangles.size(), 69000u);
  const auto box = bunny->Bounds();
  EXPECT_NEAR(box.sizes().z(), 0.16, 1e-6);
  EXPECT_NEAR(box.min().z(), 0.0, 1e-6);
  // The Stanford bunny is about as wide as it is high, and less deep.
  EXPECT_GT(box.sizes().x(), 0.12);
  EXPECT_LT(box.sizes().x(), 0.22);
}

TEST(Scenes, ObjErrorsNameTheLine) {
  auto bad = ParseObjMesh("v 0 0 0\nv 1 0 0\nf 1 2 3\n", "mem.obj");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("mem.obj:3"), std::string::npos) << bad.error().message;
  auto nan = ParseObjMesh("v 0 x 0\n", "mem.obj");
  ASSERT_FALSE(nan.ok());
  EXPECT_NE(nan.error().message.find("mem.obj:1"), std::string::npos);
  EXPECT_FALSE(ReadObjMesh("/nonexistent.obj").ok());
  auto quad = ParseObjMesh("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1/1 2/2 3/3 -1\n", "q.obj");
  ASSERT_TRUE(quad.ok()) << quad.error().message;
  EXPECT_EQ(quad->triangles.size(), 2u);
}

TEST(Scenes, TeapotHasNewellsProportions) {
  const TriangleMesh teapot = MakeTeapot(1.0, 8);
  const auto box = teapot.Bounds();
  // Height: bottom at 0, knob at 3.15. Handle reaches x = -3.0 (control points: the curve stays
  // inside their hull, reaching -2.9..-3.0); the spout's tip reaches about 3.4.
  EXPECT_NEAR(box.min().z(), 0.0, 1e-6);   // float vertices
  EXPECT_NEAR(box.max().z(), 3.15, 1e-6);  // float vertices
  EXPECT_LT(box.min().x(), -2.8);
  EXPECT_GT(box.min().x(), -3.01);
  EXPECT_GT(box.max().x(), 3.3);
  EXPECT_LT(box.max().x(), 3.53);
  EXPECT_NEAR(box.max().y(), 2.0, 1e-9);   // the body's widest ring (radius 2)
  EXPECT_NEAR(box.min().y(), -2.0, 1e-6);  // float vertices
  // Seen from the side at the height of the widest ring (z = 0.9), a ray hits the body at r = 2.
  Scene scene;
  scene.mesh = teapot;
  auto caster = RayCaster::Create(scene);
  ASSERT_TRUE(caster.ok());
  const double t = (*caster)->Cast(Eigen::Vector3d(0, -10, 0.9), Eigen::Vector3d::UnitY());
  EXPECT_NEAR(t, 8.0, 2e-3);
  // Straight down through the lid's knob and the inside to the bottom: the knob top is at 3.15.
  EXPECT_NEAR((*caster)->Cast(Eigen::Vector3d(0.01, 0.01, 5), -Eigen::Vector3d::UnitZ()), 5 - 3.15,
              1e-3);
}

TEST(Scenes, RoomsAreClosedAndTheRobotStandsInFreeSpace) {
  for (const Scene& scene : {MakeOfficeScene(), MakeLabScene()}) {
    auto caster = RayCaster::Create(scene);
    ASSERT_TRUE(caster.ok());
    // From above the robot, every direction hits something within the room's diagonal.
    const Eigen::Vector3d origin(0, 0, 0.8);
    EXPECT_TRUE(scene.IsFree(origin, 0.1)) << scene.name;
    const double diagonal = scene.workspace.sizes().norm();
    for (int k = 0; k < 500; ++k) {
      const double a = 0.37 * k, b = 0.11 * k;
      const Eigen::Vector3d d(std::cos(a) * std::cos(b), std::sin(a) * std::cos(b), std::sin(b));
      const double t = (*caster)->Cast(origin, d.normalized());
      ASSERT_FALSE(std::isinf(t)) << scene.name << " leaks towards " << d.transpose();
      EXPECT_LT(t, diagonal);
    }
  }
}

}  // namespace
}  // namespace selfcal::sim
