// Newell's teapot data, typed in from the published table of control points, reduced by the
// teapot's mirror symmetry: ten patches of one quarter (rim, body, lid, bottom) or one half
// (handle, spout); the others are their mirror images in the xz and yz planes.
#include "core/sim/teapot.h"

#include <array>

namespace selfcal::sim {
namespace {

// Control points, Newell's units, z up.
constexpr std::array<std::array<double, 3>, 127> kPoints = {{
    {0.2, 0, 2.7},
    {0.2, -0.112, 2.7},
    {0.112, -0.2, 2.7},
    {0, -0.2, 2.7},
    {1.3375, 0, 2.53125},
    {1.3375, -0.749, 2.53125},
    {0.749, -1.3375, 2.53125},
    {0, -1.3375, 2.53125},
    {1.4375, 0, 2.53125},
    {1.4375, -0.805, 2.53125},
    {0.805, -1.4375, 2.53125},
    {0, -1.4375, 2.53125},
    {1.5, 0, 2.4},
    {1.5, -0.84, 2.4},
    {0.84, -1.5, 2.4},
    {0, -1.5, 2.4},
    {1.75, 0, 1.875},
    {1.75, -0.98, 1.875},
    {0.98, -1.75, 1.875},
    {0, -1.75, 1.875},
    {2, 0, 1.35},
    {2, -1.12, 1.35},
    {1.12, -2, 1.35},
    {0, -2, 1.35},
    {2, 0, 0.9},
    {2, -1.12, 0.9},
    {1.12, -2, 0.9},
    {0, -2, 0.9},
    {-2, 0, 0.9},
    {2, 0, 0.45},
    {2, -1.12, 0.45},
    {1.12, -2, 0.45},
    {0, -2, 0.45},
    {1.5, 0, 0.225},
    {1.5, -0.84, 0.225},
    {0.84, -1.5, 0.225},
    {0, -1.5, 0.225},
    {1.5, 0, 0.15},
    {1.5, -0.84, 0.15},
    {0.84, -1.5, 0.15},
    {0, -1.5, 0.15},
    {-1.6, 0, 2.025},
    {-1.6, -0.3, 2.025},
    {-1.5, -0.3, 2.25},
    {-1.5, 0, 2.25},
    {-2.3, 0, 2.025},
    {-2.3, -0.3, 2.025},
    {-2.5, -0.3, 2.25},
    {-2.5, 0, 2.25},
    {-2.7, 0, 2.025},
    {-2.7, -0.3, 2.025},
    {-3, -0.3, 2.25},
    {-3, 0, 2.25},
    {-2.7, 0, 1.8},
    {-2.7, -0.3, 1.8},
    {-3, -0.3, 1.8},
    {-3, 0, 1.8},
    {-2.7, 0, 1.575},
    {-2.7, -0.3, 1.575},
    {-3, -0.3, 1.35},
    {-3, 0, 1.35},
    {-2.5, 0, 1.125},
    {-2.5, -0.3, 1.125},
    {-2.65, -0.3, 0.9375},
    {-2.65, 0, 0.9375},
    {-2, -0.3, 0.9},
    {-1.9, -0.3, 0.6},
    {-1.9, 0, 0.6},
    {1.7, 0, 1.425},
    {1.7, -0.66, 1.425},
    {1.7, -0.66, 0.6},
    {1.7, 0, 0.6},
    {2.6, 0, 1.425},
    {2.6, -0.66, 1.425},
    {3.1, -0.66, 0.825},
    {3.1, 0, 0.825},
    {2.3, 0, 2.1},
    {2.3, -0.25, 2.1},
    {2.4, -0.25, 2.025},
    {2.4, 0, 2.025},
    {2.7, 0, 2.4},
    {2.7, -0.25, 2.4},
    {3.3, -0.25, 2.4},
    {3.3, 0, 2.4},
    {2.8, 0, 2.475},
    {2.8, -0.25, 2.475},
    {3.525, -0.25, 2.49375},
    {3.525, 0, 2.49375},
    {2.9, 0, 2.475},
    {2.9, -0.15, 2.475},
    {3.45, -0.15, 2.5125},
    {3.45, 0, 2.5125},
    {2.8, 0, 2.4},
    {2.8, -0.15, 2.4},
    {3.2, -0.15, 2.4},
    {3.2, 0, 2.4},
    {0, 0, 3.15},
    {0.8, 0, 3.15},
    {0.8, -0.45, 3.15},
    {0.45, -0.8, 3.15},
    {0, -0.8, 3.15},
    {0, 0, 2.85},
    {1.4, 0, 2.4},
    {1.4, -0.784, 2.4},
    {0.784, -1.4, 2.4},
    {0, -1.4, 2.4},
    {0.4, 0, 2.55},
    {0.4, -0.224, 2.55},
    {0.224, -0.4, 2.55},
    {0, -0.4, 2.55},
    {1.3, 0, 2.55},
    {1.3, -0.728, 2.55},
    {0.728, -1.3, 2.55},
    {0, -1.3, 2.55},
    {1.3, 0, 2.4},
    {1.3, -0.728, 2.4},
    {0.728, -1.3, 2.4},
    {0, -1.3, 2.4},
    {0, 0, 0},
    {1.425, -0.798, 0},
    {1.5, 0, 0.075},
    {1.425, 0, 0},
    {0.798, -1.425, 0},
    {0, -1.5, 0.075},
    {0, -1.425, 0},
    {1.5, -0.84, 0.075},
    {0.84, -1.5, 0.075},
}};

struct Patch {
  std::array<int, 16> points;  // 4 x 4 control points, row-major
  bool quarter;                // true: mirrored in both planes (4 copies); false: in xz only (2)
};

constexpr std::array<Patch, 10> kPatches = {{
    {{102, 103, 104, 105, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15}, true},            // rim
    {{12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27}, true},          // upper body
    {{24, 25, 26, 27, 29, 30, 31, 32, 33, 34, 35, 36, 37, 38, 39, 40}, true},          // lower body
    {{96, 96, 96, 96, 97, 98, 99, 100, 101, 101, 101, 101, 0, 1, 2, 3}, true},         // lid knob
    {{0, 1, 2, 3, 106, 107, 108, 109, 110, 111, 112, 113, 114, 115, 116, 117}, true},  // lid
    {{118, 118, 118, 118, 124, 122, 119, 121, 123, 126, 125, 120, 40, 39, 38, 37}, true},  // bottom
    {{41, 42, 43, 44, 45, 46, 47, 48, 49, 50, 51, 52, 53, 54, 55, 56}, false},  // upper handle
    {{53, 54, 55, 56, 57, 58, 59, 60, 61, 62, 63, 64, 28, 65, 66, 67}, false},  // lower handle
    {{68, 69, 70, 71, 72, 73, 74, 75, 76, 77, 78, 79, 80, 81, 82, 83}, false},  // spout base
    {{80, 81, 82, 83, 84, 85, 86, 87, 88, 89, 90, 91, 92, 93, 94, 95}, false},  // spout tip
}};

std::array<double, 4> Bernstein(double t) {
  const double s = 1 - t;
  return {s * s * s, 3 * t * s * s, 3 * t * t * s, t * t * t};
}

void AddPatch(const Patch& patch, double sx, double sy, double scale, int n, TriangleMesh& mesh) {
  const int first = static_cast<int>(mesh.vertices.size());
  for (int i = 0; i <= n; ++i) {
    const auto bu = Bernstein(double(i) / n);
    for (int j = 0; j <= n; ++j) {
      const auto bv = Bernstein(double(j) / n);
      Eigen::Vector3d p = Eigen::Vector3d::Zero();
      for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) {
          const auto& q =
              kPoints[static_cast<std::size_t>(patch.points[static_cast<std::size_t>(4 * r + c)])];
          p += bu[static_cast<std::size_t>(r)] * bv[static_cast<std::size_t>(c)] *
               Eigen::Vector3d(q[0] * sx, q[1] * sy, q[2]);
        }
      }
      mesh.vertices.push_back((p * scale).cast<float>());
    }
  }
  // A mirror image reverses the winding; keep triangles counter-clockwise from outside.
  const bool flip = (sx * sy) < 0;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const int a = first + i * (n + 1) + j, b = a + 1, c = a + n + 1, d = c + 1;
      if (flip) {
        mesh.triangles.emplace_back(a, b, d);
        mesh.triangles.emplace_back(a, d, c);
      } else {
        mesh.triangles.emplace_back(a, d, b);
        mesh.triangles.emplace_back(a, c, d);
      }
    }
  }
}

}  // namespace

TriangleMesh MakeTeapot(double scale, int subdivisions) {
  const int n = subdivisions < 1 ? 1 : subdivisions;
  TriangleMesh mesh;
  for (const auto& patch : kPatches) {
    AddPatch(patch, 1, 1, scale, n, mesh);
    AddPatch(patch, 1, -1, scale, n, mesh);
    if (patch.quarter) {
      AddPatch(patch, -1, 1, scale, n, mesh);
      AddPatch(patch, -1, -1, scale, n, mesh);
    }
  }
  return mesh;
}

}  // namespace selfcal::sim
