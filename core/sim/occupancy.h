// The voxels of a grid that hold something: space the sensor and the arm's links must keep clear
// of, for a scene known only as points (core/sim/site_map.h).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <unordered_set>

namespace selfcal::sim {

// The key of the voxel of a grid of `voxel_m` that holds `point` (clamped some 50 km out).
std::uint64_t VoxelKey(const Eigen::Vector3d& point, double voxel_m);

// The voxels of a grid that hold points: what the sensor and the links must keep clear of.
class Occupancy {
 public:
  Occupancy() = default;  // nothing occupied
  explicit Occupancy(double voxel_m) : voxel_m_(voxel_m) {}

  void Mark(const Eigen::Vector3d& point);
  // True when an occupied voxel meets the box point +- margin.
  bool Near(const Eigen::Vector3d& point, double margin) const;
  std::size_t size() const { return cells_.size(); }
  double voxel_m() const { return voxel_m_; }

 private:
  double voxel_m_ = 0;
  std::unordered_set<std::uint64_t> cells_;
};

}  // namespace selfcal::sim
