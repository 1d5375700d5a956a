// A static simulated scene in the robot's base frame (metres), plus what the scan planner needs
// to keep the sensor in free space.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <utility>
#include <vector>

#include "core/sim/mesh.h"
#include "core/sim/occupancy.h"
#include "core/util/expected.h"

namespace selfcal::sim {

// An exact sphere (Embree's sphere primitive), for tests against analytic results.
struct Sphere {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 0;
};

// A named range [first, end) of a scene's mesh triangles: "object" (a tabletop's bunny or
// teapot), "furniture" (tables, shelves, boxes, the pedestal) or "room" (walls, floor, ceiling).
struct ScenePart {
  std::string name;
  std::size_t first = 0, end = 0;
};

struct Scene {
  std::string name;
  TriangleMesh mesh;
  std::vector<Sphere> spheres;
  std::vector<ScenePart> parts;
  // Reflectivity (albedo, 0..1) per triangle of `mesh` for the field effects; empty: 1.
  std::vector<float> albedo;
  // The sensor's origin must stay inside `workspace` and outside every obstacle (the planner
  // checks this along every trajectory; the links too when it is given a link radius).
  Eigen::AlignedBox3d workspace{Eigen::Vector3d::Constant(-1e9), Eigen::Vector3d::Constant(1e9)};
  std::vector<Eigen::AlignedBox3d> obstacles;
  // What a map of the site (core/sim/site_map.h) found occupied: kept clear of like obstacles.
  Occupancy occupied;
  // Centre of the object of interest, where depth cameras and line scanners look by default.
  Eigen::Vector3d focus = Eigen::Vector3d::Zero();

  bool IsFree(const Eigen::Vector3d& point, double margin) const;
};

// What to put where. The robot stands at the origin of the base frame; z is up; the table or
// pedestal the robot stands on has its top at z = 0.
struct SceneSpec {
  // kCell: a real cell's free space only (no surfaces), for planning scans without simulating.
  enum class Kind { kTabletop, kOffice, kLab, kCorner, kCell };
  Kind kind = Kind::kTabletop;
  enum class Object { kNone, kBunny, kTeapot };
  Object object = Object::kNone;               // tabletop only
  std::string bunny_path;                      // OBJ file of the bunny
  double object_size = 0.16;                   // m: bunny height, teapot height
  Eigen::Vector3d object_position{0.6, 0, 0};  // m: where the object stands
  double object_yaw = 0;                       // rad, about z
  // kCell: where the sensor may go and the boxes inside it it must keep out of (base frame, m).
  Eigen::AlignedBox3d cell_free_space{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  std::vector<Eigen::AlignedBox3d> cell_obstacles;
  // Albedo per part name (ScenePart); parts not named keep 1. Empty: today's scenes.
  std::vector<std::pair<std::string, double>> albedo;
};

Expected<Scene> BuildScene(const SceneSpec& spec);

// False for a cell's free space (SceneSpec::Kind::kCell): nothing a sensor could see.
bool HasSurfaces(const Scene& scene);

// Fills scene.albedo from (part name, albedo) pairs; an error names a part the scene lacks.
Status ApplyAlbedo(const std::vector<std::pair<std::string, double>>& albedo, Scene& scene);

// The scenes, each a function of its own.
Expected<TriangleMesh> MakeBunny(const std::string& obj_path, double height);
Scene MakeTabletopScene(const TriangleMesh& object, const Eigen::Vector3d& focus);
Scene MakeOfficeScene();
Scene MakeLabScene();
Scene MakeCornerScene();

}  // namespace selfcal::sim
