// Synchronized joint-space motions within velocity, acceleration and jerk limits. All joints
// follow one time scaling s(t) along the straight line in joint space, so they start and stop
// together; the slowest joint (relative to its limits) sets the pace. Profiles are seven-phase
// jerk-limited ("S-curve") when JointLimits::max_jerk is set, trapezoidal otherwise; every
// phase is a polynomial of degree <= 3, so the knots represent the motion exactly.
#pragma once

#include <Eigen/Core>

#include "core/trajectory/joint_trajectory.h"
#include "core/util/expected.h"

namespace selfcal::trajectory {

// Rest-to-rest motion from `from` to `to` in the shortest time the limits allow; the last knot
// is exactly `to`.
// Errors: sizes differ, a configuration outside the position limits.
Expected<JointTrajectory> PointToPoint(const Eigen::VectorXd& from, const Eigen::VectorXd& to,
                                       const JointLimits& limits);

// Standing still at `position` for `duration` seconds (> 0).
JointTrajectory Hold(const Eigen::VectorXd& position, double duration);

// A constant-velocity sweep over the segment [from, to]: the arm starts at rest before `from`,
// is at `speed` when it passes `from`, keeps exactly that speed up to `to`, and stops after it
// (run-up and run-out along the same line). `speed` [rad/s] is the speed of the joint that moves
// the most. Errors when the speed exceeds a joint's velocity limit or the run-up leaves the
// position limits.
struct Sweep {
  JointTrajectory trajectory;  // from rest at run-up start to rest after run-out
  double constant_begin = 0;   // s: passes `from`
  double constant_end = 0;     // s: passes `to`
};
Expected<Sweep> ConstantVelocitySweep(const Eigen::VectorXd& from, const Eigen::VectorXd& to,
                                      double speed, const JointLimits& limits);

}  // namespace selfcal::trajectory
