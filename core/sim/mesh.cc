#include "core/sim/mesh.h"

#include <cmath>
#include <numbers>

namespace selfcal::sim {

void TriangleMesh::Append(const TriangleMesh& other) {
  const int offset = static_cast<int>(vertices.size());
  vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
  triangles.reserve(triangles.size() + other.triangles.size());
  for (const auto& t : other.triangles) triangles.push_back(t.array() + offset);
}

void TriangleMesh::Transform(const Eigen::Isometry3d& T_world_mesh) {
  for (auto& v : vertices) v = (T_world_mesh * v.cast<double>()).cast<float>();
}

Eigen::AlignedBox3d TriangleMesh::Bounds() const {
  Eigen::AlignedBox3d box;
  for (const auto& v : vertices) box.extend(v.cast<double>());
  return box;
}

TriangleMesh MakeQuad(const Eigen::Vector3d& corner, const Eigen::Vector3d& edge_u,
                      const Eigen::Vector3d& edge_v, int cells) {
  TriangleMesh mesh;
  const int n = cells < 1 ? 1 : cells;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const Eigen::Vector3d p = corner + edge_u * (double(i) / n) + edge_v * (double(j) / n);
      mesh.vertices.push_back(p.cast<float>());
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      mesh.triangles.emplace_back(a, b, d);
      mesh.triangles.emplace_back(a, d, c);
    }
  }
  return mesh;
}

TriangleMesh MakeBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max) {
  const Eigen::Vector3d d = max - min;
  const Eigen::Vector3d ex(d.x(), 0, 0), ey(0, d.y(), 0), ez(0, 0, d.z());
  TriangleMesh mesh;
  mesh.Append(MakeQuad(min, ey, ex));       // bottom, normal -z
  mesh.Append(MakeQuad(min + ez, ex, ey));  // top, +z
  mesh.Append(MakeQuad(min, ex, ez));       // front, -y
  mesh.Append(MakeQuad(min + ey, ez, ex));  // back, +y
  mesh.Append(MakeQuad(min, ez, ey));       // left, -x
  mesh.Append(MakeQuad(min + ex, ey, ez));  // right, +x
  return mesh;
}

TriangleMesh MakeCylinder(const Eigen::Vector3d& base_center, double radius, double height,
                          int segments) {
  TriangleMesh mesh;
  const int n = segments < 3 ? 3 : segments;
  for (int k = 0; k < n; ++k) {
    const double a = 2 * std::numbers::pi * k / n;
    const Eigen::Vector3d r(radius * std::cos(a), radius * std::sin(a), 0);
    mesh.vertices.push_back((base_center + r).cast<float>());
    mesh.vertices.push_back((base_center + r + Eigen::Vector3d(0, 0, height)).cast<float>());
  }
  const int bottom = static_cast<int>(mesh.vertices.size());
  mesh.vertices.push_back(base_center.cast<float>());
  mesh.vertices.push_back((base_center + Eigen::Vector3d(0, 0, height)).cast<float>());
  for (int k = 0; k < n; ++k) {
    const int a0 = 2 * k, a1 = 2 * k + 1, b0 = 2 * ((k + 1) % n), b1 = b0 + 1;
    mesh.triangles.emplace_back(a0, b0, b1);
    mesh.triangles.emplace_back(a0, b1, a1);
    mesh.triangles.emplace_back(bottom, b0, a0);
    mesh.triangles.emplace_back(bottom + 1, a1, b1);
  }
  return mesh;
}

}  // namespace selfcal::sim
