// Scan programs become trajectories. A small input of our own (the simulator's scan plans in
// core/sim convert into it): a list of steps, each a point-to-point move with a settle time
// (depth-camera frames, or transfer moves) or a constant-velocity sweep (the paper's one-axis
// LiDAR sweeps and line-scanner sweeps). The result is one continuous trajectory plus the time
// windows in which each scan's data is taken.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/trajectory/joint_trajectory.h"
#include "core/trajectory/motion.h"

namespace selfcal::trajectory {

struct ScanStep {
  enum class Kind { kMoveTo, kSweep };
  Kind kind = Kind::kMoveTo;
  // kMoveTo: the goal configuration. kSweep: where the constant-velocity part ends.
  Eigen::VectorXd target;
  // kSweep: where the constant-velocity part begins (the arm moves to the run-up point first).
  Eigen::VectorXd from;
  // kSweep: speed [rad/s] of the joint that moves the most during the sweep.
  double speed = 0;
  // kMoveTo: standing still after arrival before the data counts [s], then for `dwell` [s]
  // while a frame is taken. A transfer move has scan_index -1 and no dwell.
  double settle_time = 0;
  double dwell = 0;
  // Index of the scan in the plan (scan_marker_t.scan_index), -1 for a transfer move.
  int scan_index = -1;
};

struct ScanProgram {
  std::string name;
  std::vector<ScanStep> steps;
};

// The paper's one-axis LiDAR sweep: joint `joint` turns from `from_angle` to `to_angle` [rad] at
// `speed` [rad/s] while the others stay at `posture`.
ScanStep OneAxisSweep(const Eigen::VectorXd& posture, int joint, double from_angle, double to_angle,
                      double speed, int scan_index);
// A line-scanner sweep: a straight joint-space line from `from` to `to` at constant speed.
ScanStep LineSweep(const Eigen::VectorXd& from, const Eigen::VectorXd& to, double speed,
                   int scan_index);
// A depth-camera pose: move, settle, take one frame during `dwell`.
ScanStep CameraPose(const Eigen::VectorXd& configuration, double settle_time, double dwell,
                    int scan_index);

struct ScanWindow {
  int scan_index = -1;
  double begin = 0;  // s from the start of the program trajectory
  double end = 0;
};

struct PlannedProgram {
  JointTrajectory trajectory;       // from `start`, continuous, at rest at the end
  std::vector<ScanWindow> windows;  // one per step with scan_index >= 0, in order
};

// Plans the whole program starting at rest at `start`. Errors name the step index.
Expected<PlannedProgram> PlanScanProgram(const ScanProgram& program, const Eigen::VectorXd& start,
                                         const JointLimits& limits);

}  // namespace selfcal::trajectory
