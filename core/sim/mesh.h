// Triangle meshes of the simulated scenes, in metres.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

namespace selfcal::sim {

struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<Eigen::Vector3i> triangles;  // vertex indices, counter-clockwise seen from outside

  void Append(const TriangleMesh& other);
  // Applies `T_world_mesh` to every vertex.
  void Transform(const Eigen::Isometry3d& T_world_mesh);
  Eigen::AlignedBox3d Bounds() const;
};

// An axis-aligned box [min, max] with outward faces, 12 triangles.
TriangleMesh MakeBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max);

// A rectangle through `corner` spanned by `edge_u` and `edge_v` (normal = edge_u x edge_v),
// split into 2 * cells * cells triangles (small triangles keep float intersections precise).
TriangleMesh MakeQuad(const Eigen::Vector3d& corner, const Eigen::Vector3d& edge_u,
                      const Eigen::Vector3d& edge_v, int cells = 1);

// A closed cylinder along z from z0 to z1 (table legs, cans), `segments` around.
TriangleMesh MakeCylinder(const Eigen::Vector3d& base_center, double radius, double height,
                          int segments);

}  // namespace selfcal::sim
