#include "core/sim/occupancy.h"

#include <algorithm>
#include <cmath>

namespace selfcal::sim {
namespace {

// 21 bits per axis, signed: +-1,048,575 voxels (52 km at 5 cm) around the base.
constexpr std::int64_t kAxisLimit = (1 << 20) - 1;

std::int64_t AxisIndex(double coordinate, double voxel_m) {
  const double index = std::floor(coordinate / voxel_m);
  return static_cast<std::int64_t>(
      std::clamp(index, -static_cast<double>(kAxisLimit), static_cast<double>(kAxisLimit)));
}

std::uint64_t Key(std::int64_t x, std::int64_t y, std::int64_t z) {
  const auto bits = [](std::int64_t v) { return static_cast<std::uint64_t>(v + kAxisLimit); };
  return bits(x) << 42 | bits(y) << 21 | bits(z);
}

}  // namespace

std::uint64_t VoxelKey(const Eigen::Vector3d& point, double voxel_m) {
  return Key(AxisIndex(point.x(), voxel_m), AxisIndex(point.y(), voxel_m),
             AxisIndex(point.z(), voxel_m));
}

void Occupancy::Mark(const Eigen::Vector3d& point) { cells_.insert(VoxelKey(point, voxel_m_)); }

bool Occupancy::Near(const Eigen::Vector3d& point, double margin) const {
  if (cells_.empty()) return false;
  const Eigen::Vector3d low = point.array() - margin, high = point.array() + margin;
  for (std::int64_t x = AxisIndex(low.x(), voxel_m_); x <= AxisIndex(high.x(), voxel_m_); ++x) {
    for (std::int64_t y = AxisIndex(low.y(), voxel_m_); y <= AxisIndex(high.y(), voxel_m_); ++y) {
      for (std::int64_t z = AxisIndex(low.z(), voxel_m_); z <= AxisIndex(high.z(), voxel_m_); ++z) {
        if (cells_.contains(Key(x, y, z))) return true;
      }
    }
  }
  return false;
}

}  // namespace selfcal::sim
