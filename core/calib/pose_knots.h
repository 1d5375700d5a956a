// Poses of scans that move while they are measured (line scanner: a pose per column, rotating
// LiDAR: a pose per point), evaluated at knots and interpolated in between.
//
// The recording interpolates joints linearly between joint-state samples, so between two
// samples a scan's joints move on a straight line. We keep as knots the poses where that line
// bends (Douglas-Peucker on the joint sequence in time order, tolerance kJointTolerance) and
// enough more that no segment turns a joint by more than kMaxJointStep; a pose in between is
// T = (1 - alpha) T_a + alpha T_b, alpha its position on the segment in joint space. Against the
// forward kinematics of its own joints this differs by about (step^2 / 8) * distance from the
// turning axis: below a micrometre for the scenarios here (PoseKnots.* in
// tests/calib/fast_problem_test.cc measures it), while forward kinematics (and its 6 x K Jacobian)
// runs once per knot instead of once per point. A deliberate deviation from the paper:
// docs/engine.md.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/calib/dataset.h"

namespace selfcal::calib {

constexpr double kJointTolerance = 1e-9;  // rad (or m): off-line joints that make a knot
constexpr double kMaxJointStep = 1e-3;    // rad (or m): largest joint change between knots

struct PoseKnots {
  std::vector<std::uint32_t> knot_pose;  // pose index of every knot, in time order
  // Per pose: its segment [segment, segment + 1] of knots and the weight of the second knot
  // (0 for a knot itself and for single-pose scans).
  std::vector<std::uint32_t> segment;
  std::vector<float> alpha;

  std::size_t KnotCount() const { return knot_pose.size(); }
  std::uint32_t SecondKnot(std::uint32_t s) const { return s + 1 < knot_pose.size() ? s + 1 : s; }
};

// Pose indices of a dataset in the order they were measured (docs/recording.md: LiDAR points
// by column, then by row; line-scanner columns in order).
std::vector<std::uint32_t> PosesInTimeOrder(const Dataset& dataset);

PoseKnots BuildPoseKnots(const Dataset& dataset, double tolerance = kJointTolerance,
                         double max_step = kMaxJointStep);
// BuildPoseKnots of every dataset, on `threads` threads (results do not depend on the count).
std::vector<PoseKnots> BuildAllPoseKnots(const std::vector<Dataset>& datasets, int threads,
                                         double max_step = kMaxJointStep);

// (1 - alpha) a + alpha b, for 3 x 4 transforms and their origins.
template <int Cols>
Eigen::Matrix<double, 3, Cols> Blend(const Eigen::Matrix<double, 3, Cols>& a,
                                     const Eigen::Matrix<double, 3, Cols>& b, double alpha) {
  return alpha == 0.0 ? a : Eigen::Matrix<double, 3, Cols>((1.0 - alpha) * a + alpha * b);
}

}  // namespace selfcal::calib
