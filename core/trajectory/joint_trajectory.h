// A joint-space trajectory as piecewise cubic Hermite segments between knots (time, position,
// velocity). Cubic Hermite reproduces polynomials up to degree 3 exactly, so a trapezoidal
// velocity profile with knots at its phase boundaries is represented without error, and the same
// knots travel over LCM (selfcal.joint_trajectory_t) and are interpolated identically by the
// driver at the FRI rate.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/model/robot_model.h"
#include "core/util/expected.h"

namespace selfcal::trajectory {

// Limits per joint, base to tip; SI units (rad, rad/s, rad/s^2, rad/s^3). An empty max_jerk
// plans trapezoidal velocity profiles (unbounded jerk at the phase changes).
struct JointLimits {
  Eigen::VectorXd lower, upper, max_velocity, max_acceleration, max_jerk;
  std::size_t size() const { return static_cast<std::size_t>(lower.size()); }
};

// The robot model file has no jerk limits: we reach full acceleration in this time, so
// max_jerk = max_acceleration / kDefaultJerkTime (a choice of ours, named in docs/robot-side.md).
inline constexpr double kDefaultJerkTime = 0.1;  // s

// The limits of the robot model file, velocity and acceleration scaled by `fraction` (0, 1],
// jerk from kDefaultJerkTime.
JointLimits LimitsFromModel(const RobotModel& model, double fraction = 1.0);

struct Knot {
  double time = 0.0;         // s from the start of the trajectory
  Eigen::VectorXd position;  // rad (m for prismatic joints)
  Eigen::VectorXd velocity;  // rad/s
};

struct Sample {
  Eigen::VectorXd position, velocity, acceleration;
};

class JointTrajectory {
 public:
  JointTrajectory() = default;
  // Checks: at least one knot, equal sizes, finite values, strictly increasing times from 0.
  static Expected<JointTrajectory> FromKnots(std::vector<Knot> knots);

  // Position, velocity and acceleration at `time` (s); clamped to [0, duration()]: before the
  // start the first knot, after the end the last knot with zero velocity.
  Sample Evaluate(double time) const;
  double duration() const { return knots_.empty() ? 0.0 : knots_.back().time; }
  std::size_t joint_count() const {
    return knots_.empty() ? 0 : static_cast<std::size_t>(knots_.front().position.size());
  }
  const std::vector<Knot>& knots() const { return knots_; }
  const Knot& front() const { return knots_.front(); }
  const Knot& back() const { return knots_.back(); }

  // Appends `next` shifted to start at duration(); its first knot must equal our last one
  // (position and velocity within `tolerance`) and is merged with it.
  Status Append(const JointTrajectory& next, double tolerance = 1e-9);

 private:
  std::vector<Knot> knots_;
};

// Whether the trajectory stays within `limits`, checked exactly per segment: positions at the
// extrema of each cubic, velocities at the extremum of each quadratic, accelerations at the
// segment ends (linear per segment). `tolerance` is relative (1e-6 = 1 ppm over the limit).
// The error names the joint, the segment, the time and the limit.
Status CheckLimits(const JointTrajectory& trajectory, const JointLimits& limits,
                   const std::vector<std::string>& joint_names = {}, double tolerance = 1e-6);

// Largest jerk [rad/s^3] of any joint (constant within each cubic segment).
double MaxJerk(const JointTrajectory& trajectory);

}  // namespace selfcal::trajectory
