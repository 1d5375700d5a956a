#include "core/sim/scene.h"

#include <algorithm>
#include <numbers>
#include <string>

#include "core/sim/obj_mesh.h"
#include "core/sim/teapot.h"

namespace selfcal::sim {
namespace {

using Eigen::Vector3d;

// A table: top slab and four legs.
TriangleMesh MakeTable(const Vector3d& min_corner, double length_x, double width_y, double height,
                       std::vector<Eigen::AlignedBox3d>* obstacles) {
  TriangleMesh mesh;
  const double top = 0.03, leg = 0.05;
  const Vector3d top_min = min_corner + Vector3d(0, 0, height - top);
  const Vector3d top_max = min_corner + Vector3d(length_x, width_y, height);
  mesh.Append(MakeBox(top_min, top_max));
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) {
      const Vector3d leg_min = min_corner + Vector3d(i * (length_x - leg), j * (width_y - leg), 0);
      mesh.Append(MakeBox(leg_min, leg_min + Vector3d(leg, leg, height - top)));
    }
  }
  if (obstacles) obstacles->emplace_back(min_corner, top_max);
  return mesh;
}

// A shelf: two sides, a back and `boards` boards, open towards -y in its own frame, turned by
// `yaw` about z at `origin`.
TriangleMesh MakeShelf(const Vector3d& origin, double yaw, double width, double depth,
                       double height, int boards, std::vector<Eigen::AlignedBox3d>* obstacles) {
  TriangleMesh mesh;
  const double t = 0.02;
  mesh.Append(MakeBox(Vector3d(0, 0, 0), Vector3d(t, depth, height)));
  mesh.Append(MakeBox(Vector3d(width - t, 0, 0), Vector3d(width, depth, height)));
  mesh.Append(MakeBox(Vector3d(0, depth - t, 0), Vector3d(width, depth, height)));
  for (int b = 0; b < boards; ++b) {
    const double z = b * (height - t) / (boards - 1);
    mesh.Append(MakeBox(Vector3d(t, 0, z), Vector3d(width - t, depth - t, z + t)));
  }
  // Things on the boards, so the shelf is not a set of parallel planes.
  for (int b = 0; b + 1 < boards; ++b) {
    const double z = b * (height - t) / (boards - 1) + t;
    const double x0 = 0.08 + 0.11 * b;
    mesh.Append(MakeBox(Vector3d(x0, 0.05, z), Vector3d(x0 + 0.18, depth - 0.08, z + 0.22)));
    mesh.Append(MakeCylinder(Vector3d(width - 0.2 - 0.05 * b, depth / 2, z), 0.05, 0.15, 24));
  }
  const Eigen::Isometry3d T =
      Eigen::Translation3d(origin) * Eigen::AngleAxisd(yaw, Vector3d::UnitZ());
  mesh.Transform(T);
  if (obstacles) {
    Eigen::AlignedBox3d box;
    for (const auto& v : mesh.vertices) box.extend(v.cast<double>());
    obstacles->push_back(box);
  }
  return mesh;
}

// Walls, floor and ceiling of a room [min, max] (inward faces; the mesh is two-sided for rays).
TriangleMesh MakeRoom(const Vector3d& min, const Vector3d& max) {
  const Vector3d d = max - min;
  const Vector3d ex(d.x(), 0, 0), ey(0, d.y(), 0), ez(0, 0, d.z());
  // Fine cells: long thin triangles cost float precision far from their vertices.
  const int cells = 8;
  TriangleMesh mesh;
  mesh.Append(MakeQuad(min, ex, ey, cells));       // floor
  mesh.Append(MakeQuad(min + ez, ey, ex, cells));  // ceiling
  mesh.Append(MakeQuad(min, ez, ex, cells));       // wall y = min
  mesh.Append(MakeQuad(min + ey, ex, ez, cells));  // wall y = max
  mesh.Append(MakeQuad(min, ey, ez, cells));       // wall x = min
  mesh.Append(MakeQuad(min + ex, ez, ey, cells));  // wall x = max
  return mesh;
}

// Names the triangles from `first` to the mesh's end.
void MarkPart(const std::string& name, std::size_t first, Scene& scene) {
  scene.parts.push_back({name, first, scene.mesh.triangles.size()});
}

// A box the rays see and the planner keeps the arm out of.
void AddSolidBox(const Vector3d& min, const Vector3d& max, Scene& scene) {
  scene.mesh.Append(MakeBox(min, max));
  scene.obstacles.emplace_back(min, max);
}

// The robot's pedestal: a box under the base, from the floor to z = 0.
void AddPedestal(double floor_z, Scene& scene) {
  AddSolidBox(Vector3d(-0.25, -0.25, floor_z), Vector3d(0.25, 0.25, 0), scene);
}

// A room from its floor to `room_max` with the robot's pedestal in it; the whole room is
// workspace.
Scene MakeRoomScene(const std::string& name, const Vector3d& room_min, const Vector3d& room_max) {
  Scene scene;
  scene.name = name;
  scene.mesh = MakeRoom(room_min, room_max);
  MarkPart("room", 0, scene);
  scene.workspace = Eigen::AlignedBox3d(room_min, room_max);
  AddPedestal(room_min.z(), scene);
  return scene;
}

}  // namespace

bool Scene::IsFree(const Eigen::Vector3d& point, double margin) const {
  const Eigen::Vector3d m = Eigen::Vector3d::Constant(margin);
  if (!Eigen::AlignedBox3d(workspace.min() + m, workspace.max() - m).contains(point)) return false;
  for (const auto& box : obstacles) {
    if (Eigen::AlignedBox3d(box.min() - m, box.max() + m).contains(point)) return false;
  }
  return !occupied.Near(point, margin);
}

Expected<TriangleMesh> MakeBunny(const std::string& obj_path, double height) {
  auto mesh = ReadObjMesh(obj_path);
  if (!mesh) return mesh.error();
  // The Stanford data has y up; ours has z up.
  Eigen::Isometry3d y_up_to_z_up(Eigen::AngleAxisd(std::numbers::pi / 2, Vector3d::UnitX()));
  mesh->Transform(y_up_to_z_up);
  const Eigen::AlignedBox3d box = mesh->Bounds();
  if (!(box.sizes().z() > 0)) return Error{obj_path + ": the mesh has no height"};
  const double scale = height / box.sizes().z();
  const Vector3d bottom_center(box.center().x(), box.center().y(), box.min().z());
  for (auto& v : mesh->vertices) v = ((v.cast<double>() - bottom_center) * scale).cast<float>();
  return mesh;
}

Scene MakeTabletopScene(const TriangleMesh& object, const Eigen::Vector3d& focus) {
  Scene scene;
  scene.name = "tabletop";
  scene.mesh = object;
  MarkPart("object", 0, scene);
  // The robot and the object share a table (top at z = 0) in a room.
  const double floor_z = -0.85;
  std::size_t first = scene.mesh.triangles.size();
  scene.mesh.Append(MakeBox(Vector3d(-0.4, -0.8, -0.05), Vector3d(1.2, 0.8, 0.0)));
  MarkPart("furniture", first, scene);
  scene.obstacles.emplace_back(Vector3d(-0.4, -0.8, floor_z), Vector3d(1.2, 0.8, 0.0));
  first = scene.mesh.triangles.size();
  scene.mesh.Append(MakeRoom(Vector3d(-1.5, -2.0, floor_z), Vector3d(2.5, 2.0, 2.0)));
  MarkPart("room", first, scene);
  scene.workspace = Eigen::AlignedBox3d(Vector3d(-1.5, -2.0, 0.0), Vector3d(2.5, 2.0, 2.0));
  scene.focus = focus;
  return scene;
}

Scene MakeOfficeScene() {
  const double floor_z = -0.8;
  const Vector3d room_min(-1.2, -2.0, floor_z), room_max(3.8, 2.2, floor_z + 2.8);
  Scene scene = MakeRoomScene("office", room_min, room_max);
  // Two desks, a shelf, a cabinet, boxes and a door frame: the paper's office has furniture at
  // all heights.
  scene.mesh.Append(MakeTable(Vector3d(1.2, -1.9, floor_z), 1.6, 0.8, 0.75, &scene.obstacles));
  scene.mesh.Append(MakeTable(Vector3d(2.9, -0.6, floor_z), 0.8, 1.6, 0.75, &scene.obstacles));
  scene.mesh.Append(
      MakeShelf(Vector3d(0.4, 2.2 - 0.4, floor_z), 0, 1.2, 0.4, 2.0, 5, &scene.obstacles));
  const Vector3d cabinet_min(2.6, 1.5, floor_z), cabinet_max(3.8, 2.2, floor_z + 1.1);
  AddSolidBox(cabinet_min, cabinet_max, scene);
  const Vector3d box_min(1.4, -1.7, floor_z + 0.75), box_max(1.8, -1.4, floor_z + 1.05);
  AddSolidBox(box_min, box_max, scene);
  AddSolidBox(Vector3d(3.1, -0.4, floor_z + 0.75), Vector3d(3.4, 0.1, floor_z + 1.15), scene);
  // A pillar and a window niche break the symmetry of the walls.
  AddSolidBox(Vector3d(-1.2, 0.6, floor_z), Vector3d(-0.9, 1.0, room_max.z()), scene);
  AddSolidBox(Vector3d(0.5, -2.0, floor_z + 0.9), Vector3d(1.0, -1.85, floor_z + 2.2), scene);
  MarkPart("furniture", scene.parts.back().end, scene);
  scene.focus = Vector3d(1.5, 0.0, 0.0);
  return scene;
}

Scene MakeLabScene() {
  const double floor_z = -0.9;
  const Vector3d room_min(-2.0, -3.0, floor_z), room_max(5.0, 3.0, floor_z + 3.5);
  Scene scene = MakeRoomScene("lab", room_min, room_max);
  // A workcell: the robot's table, a fence of posts, workbenches, shelves, machines, boxes.
  scene.mesh.Append(MakeTable(Vector3d(0.45, -0.6, floor_z), 0.8, 1.2, 0.9, &scene.obstacles));
  for (int i = 0; i < 5; ++i) {
    const Vector3d post_min(-1.0 + 0.7 * i, -1.6, floor_z);
    AddSolidBox(post_min, post_min + Vector3d(0.06, 0.06, 2.0), scene);
  }
  scene.mesh.Append(
      MakeBox(Vector3d(-1.0, -1.6, floor_z + 1.95), Vector3d(1.86, -1.54, floor_z + 2.0)));
  scene.mesh.Append(MakeTable(Vector3d(2.0, -2.9, floor_z), 2.0, 0.8, 0.9, &scene.obstacles));
  scene.mesh.Append(MakeTable(Vector3d(2.2, 1.4, floor_z), 1.8, 0.9, 0.9, &scene.obstacles));
  scene.mesh.Append(
      MakeShelf(Vector3d(-1.6, 3.0 - 0.5, floor_z), 0, 1.5, 0.5, 2.4, 6, &scene.obstacles));
  scene.mesh.Append(MakeShelf(Vector3d(5.0 - 0.5, 1.2, floor_z), std::numbers::pi / 2, 1.5, 0.5,
                              2.4, 6, &scene.obstacles));
  const Vector3d machine_min(3.4, -1.2, floor_z), machine_max(4.6, 0.4, floor_z + 1.7);
  AddSolidBox(machine_min, machine_max, scene);
  scene.mesh.Append(MakeCylinder(Vector3d(3.0, 0.9, floor_z), 0.25, 1.2, 32));
  scene.obstacles.emplace_back(Vector3d(2.75, 0.65, floor_z), Vector3d(3.25, 1.15, floor_z + 1.2));
  for (int i = 0; i < 4; ++i) {
    const Vector3d box_min(2.2 + 0.45 * i, -2.8, floor_z + 0.9);
    const Vector3d box_max = box_min + Vector3d(0.3, 0.4 + 0.05 * i, 0.2 + 0.1 * i);
    AddSolidBox(box_min, box_max, scene);
  }
  // Ceiling beams.
  for (int i = 0; i < 3; ++i) {
    const Vector3d beam_min(-2.0, -2.0 + 2.0 * i, room_max.z() - 0.3);
    scene.mesh.Append(MakeBox(beam_min, beam_min + Vector3d(7.0, 0.25, 0.3)));
  }
  MarkPart("furniture", scene.parts.back().end, scene);
  scene.focus = Vector3d(1.5, 0.0, 0.0);
  return scene;
}

Scene MakeCornerScene() {
  Scene scene;
  scene.name = "corner";
  // The robot on a table at z = 0 in front of a room corner with boxes: small and quick.
  const double floor_z = -0.75;
  const Vector3d room_min(-0.6, -1.5, floor_z), room_max(1.6, 1.0, 1.6);
  scene.mesh.Append(MakeQuad(room_min, Vector3d(room_max.x() - room_min.x(), 0, 0),
                             Vector3d(0, room_max.y() - room_min.y(), 0), 8));  // floor
  scene.mesh.Append(MakeQuad(Vector3d(room_max.x(), room_min.y(), floor_z),
                             Vector3d(0, 0, room_max.z() - floor_z),
                             Vector3d(0, room_max.y() - room_min.y(), 0), 8));  // wall x = max
  scene.mesh.Append(MakeQuad(Vector3d(room_min.x(), room_max.y(), floor_z),
                             Vector3d(room_max.x() - room_min.x(), 0, 0),
                             Vector3d(0, 0, room_max.z() - floor_z), 8));  // wall y = max
  MarkPart("room", 0, scene);
  const Vector3d table_min(-0.4, -1.0, -0.05), table_max(1.2, 0.8, 0.0);
  scene.mesh.Append(MakeBox(table_min, table_max));
  scene.obstacles.emplace_back(Vector3d(-0.4, -1.0, floor_z), table_max);
  const Vector3d boxes[][2] = {{{0.7, 0.15, 0.0}, {0.95, 0.45, 0.25}},
                               {{0.95, -0.3, 0.0}, {1.15, -0.05, 0.12}},
                               {{0.55, -0.45, 0.0}, {0.7, -0.3, 0.35}},
                               {{1.0, 0.5, 0.0}, {1.15, 0.75, 0.5}}};
  for (const auto& b : boxes) {
    AddSolidBox(b[0], b[1], scene);
  }
  scene.mesh.Append(MakeCylinder(Vector3d(0.8, -0.1, 0.0), 0.06, 0.2, 32));
  MarkPart("furniture", scene.parts.back().end, scene);
  scene.workspace = Eigen::AlignedBox3d(Vector3d(room_min.x(), room_min.y(), 0.0), room_max);
  scene.focus = Vector3d(0.95, 0.2, 0.15);
  return scene;
}

Status ApplyAlbedo(const std::vector<std::pair<std::string, double>>& albedo, Scene& scene) {
  if (albedo.empty()) return OkStatus();
  scene.albedo.assign(scene.mesh.triangles.size(), 1.0f);
  for (const auto& [name, value] : albedo) {
    bool found = false;
    for (const ScenePart& part : scene.parts) {
      if (part.name != name) continue;
      found = true;
      std::fill(scene.albedo.begin() + static_cast<std::ptrdiff_t>(part.first),
                scene.albedo.begin() + static_cast<std::ptrdiff_t>(part.end),
                static_cast<float>(value));
    }
    if (!found) return Error{"albedo: the " + scene.name + " scene has no part '" + name + "'"};
  }
  return OkStatus();
}

namespace {

Expected<Scene> MakeCellScene(const SceneSpec& spec) {
  if (spec.cell_free_space.isEmpty() || spec.cell_free_space.volume() <= 0) {
    return Error{"a cell's free space must be a box of positive volume"};
  }
  Scene scene;
  scene.name = "cell";
  scene.workspace = spec.cell_free_space;
  scene.obstacles = spec.cell_obstacles;
  scene.focus = spec.cell_free_space.center();
  return scene;
}

Expected<Scene> BuildSceneGeometry(const SceneSpec& spec) {
  switch (spec.kind) {
    case SceneSpec::Kind::kOffice:
      return MakeOfficeScene();
    case SceneSpec::Kind::kLab:
      return MakeLabScene();
    case SceneSpec::Kind::kCorner:
      return MakeCornerScene();
    case SceneSpec::Kind::kCell:
      return MakeCellScene(spec);
    case SceneSpec::Kind::kTabletop:
      break;
  }
  TriangleMesh object;
  if (spec.object == SceneSpec::Object::kBunny) {
    auto bunny = MakeBunny(spec.bunny_path, spec.object_size);
    if (!bunny) return bunny.error();
    object = std::move(*bunny);
  } else if (spec.object == SceneSpec::Object::kTeapot) {
    // Newell's teapot is 3.15 units high.
    object = MakeTeapot(spec.object_size / 3.15, 12);
  }
  const Eigen::Isometry3d T_base_object = Eigen::Translation3d(spec.object_position) *
                                          Eigen::AngleAxisd(spec.object_yaw, Vector3d::UnitZ());
  object.Transform(T_base_object);
  Vector3d focus = spec.object_position + Vector3d(0, 0, spec.object_size / 2);
  const Eigen::AlignedBox3d object_box = object.Bounds();
  Scene scene = MakeTabletopScene(object, focus);
  if (!object.vertices.empty()) scene.obstacles.push_back(object_box);
  scene.name = spec.object == SceneSpec::Object::kBunny    ? "bunny"
               : spec.object == SceneSpec::Object::kTeapot ? "teapot"
                                                           : "tabletop";
  return scene;
}

}  // namespace

bool HasSurfaces(const Scene& scene) {
  return !scene.mesh.triangles.empty() || !scene.spheres.empty();
}

Expected<Scene> BuildScene(const SceneSpec& spec) {
  auto scene = BuildSceneGeometry(spec);
  if (!scene) return scene;
  if (auto applied = ApplyAlbedo(spec.albedo, *scene); !applied) return applied.error();
  return scene;
}

}  // namespace selfcal::sim
