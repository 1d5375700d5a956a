// A dataset: one scan of the sensor with the joint states of every measurement (the paper's
// "Data Structure and Notation": D_i and J_i). Points keep their grid position (row, column) so
// that normals and the edge filter work on the grid; every pose has its interpolated joints
// (JointsOfPose: stored, or for a LiDAR with joint timing computed when read).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "core/calib/joint_interpolation.h"

namespace selfcal::calib {

// The most joints a robot model may have for the engine (calibrate.cc checks it): the size of a
// buffer for one pose's joints.
inline constexpr std::size_t kMaxJoints = 16;

// One pose's joint state as the engine's chain reads it (chain.h): the positions, and where the
// recording kept them, the pose's measurement time and the recording's joint states, so that a
// latency parameter (joint_correction.h) can interpolate the joints at another latency.
struct PoseState {
  const double* q = nullptr;                 // joint_count positions [rad or m]
  double utime = 0;                          // measurement time [us, host; may be fractional]
  const JointStateSeries* series = nullptr;  // null: the joints are all there is
  int recording = 0;
};

// How many joint configurations (poses) a scan has, by sensor layout (docs/recording.md):
// depth camera one per scan, line scanner one per column (profile), rotating LiDAR one per point.
enum class PoseLayout { kOnePerScan, kOnePerColumn, kOnePerPoint };

struct Dataset {
  int scan_index = 0;       // scan_index of the recording's markers
  bool validation = false;  // held back: never fitted, only used to validate the result
  PoseLayout layout = PoseLayout::kOnePerScan;
  std::size_t rows = 0;
  std::size_t cols = 0;
  // Points in the sensor frame [m], row-major (point index = row * cols + col), rows * cols
  // entries each; NaN = no measurement. Float: sensor noise is far above float resolution.
  std::vector<float> x, y, z;
  std::size_t joint_count = 0;  // at most kMaxJoints
  // Joint positions [rad or m] of every pose, PoseCount() * joint_count entries, pose-major; or
  // empty where the joint timing below gives them (a rotating LiDAR's recording with it: 7
  // doubles a point, most of a LiDAR recording's memory otherwise): read them with JointsOfPose.
  std::vector<double> pose_joints;
  // The latency [s] pose_joints were interpolated at (measurement time + latency,
  // docs/recording.md), and which recording of a calibration the scan comes from (one latency
  // parameter per recording; 0 for a single recording).
  double joint_latency_s = 0.0;
  int recording = 0;
  // Kept on request (RecordingOptions::joint_timing), else empty and null: every pose's
  // measurement time [us, host, without the latency] and the recording's joint states (shared by
  // its scans), from which the sensor latency's parameter re-interpolates the joints.
  std::vector<double> pose_utime;
  // A rotating LiDAR's, with the joint timing: pose_utime holds each column's (rotation's) first
  // ray and this the time between its rays [s], so that a point's time is computed when read
  // (PoseUtime), not stored. Empty otherwise.
  std::vector<double> ray_period_s;
  std::shared_ptr<const JointStateSeries> joint_states;

  bool HasJointTiming() const { return joint_states != nullptr && !pose_utime.empty(); }
  // The measurement time of `pose` [us, host, without the latency], as the recording computed it.
  double PoseUtime(std::size_t pose) const {
    if (ray_period_s.empty()) return pose_utime[pose];
    const std::size_t column = pose % cols;
    return pose_utime[column] + 1e6 * static_cast<double>(pose / cols) * ray_period_s[column];
  }
  // Every pose has its joints: stored, or computable from the joint timing.
  bool HasJointsOfEveryPose() const {
    if (!pose_joints.empty() || !HasJointTiming()) {
      return pose_joints.size() == PoseCount() * joint_count;
    }
    const bool per_column = !ray_period_s.empty();
    return pose_utime.size() == (per_column ? cols : PoseCount()) &&
           (!per_column || (layout == PoseLayout::kOnePerPoint && ray_period_s.size() == cols)) &&
           joint_states->joint_count == joint_count && joint_states->size() > 0;
  }

  std::size_t PointCount() const { return rows * cols; }
  std::size_t PoseCount() const {
    switch (layout) {
      case PoseLayout::kOnePerScan:
        return 1;
      case PoseLayout::kOnePerColumn:
        return cols;
      case PoseLayout::kOnePerPoint:
        return rows * cols;
    }
    return 1;
  }
  std::size_t PoseOf(std::size_t point) const {
    switch (layout) {
      case PoseLayout::kOnePerScan:
        return 0;
      case PoseLayout::kOnePerColumn:
        return point % cols;
      case PoseLayout::kOnePerPoint:
        return point;
    }
    return 0;
  }
  // The joints of `pose`: in pose_joints, or interpolated into `buffer` (joint_count entries) at
  // the pose's time + joint_latency_s exactly as the recording interpolates them.
  const double* JointsOfPose(std::size_t pose, double* buffer) const {
    if (!pose_joints.empty()) return pose_joints.data() + pose * joint_count;
    JointsAt(*joint_states, PoseUtime(pose) + joint_latency_s * 1e6,
             std::span<double>(buffer, joint_count));
    return buffer;
  }
  PoseState Joints(std::size_t pose, double* buffer) const {
    if (!HasJointTiming()) return {JointsOfPose(pose, buffer), 0, nullptr, recording};
    return {JointsOfPose(pose, buffer), PoseUtime(pose), joint_states.get(), recording};
  }
  bool IsValid(std::size_t point) const {
    return x[point] == x[point] && y[point] == y[point] && z[point] == z[point];
  }
  std::size_t ValidPointCount() const {
    std::size_t count = 0;
    for (std::size_t i = 0; i < PointCount(); ++i) count += IsValid(i) ? 1 : 0;
    return count;
  }
};

}  // namespace selfcal::calib
