// Inverse kinematics for scan planning: damped least squares on a numeric Jacobian, with
// restarts, within joint limits. Used the way the paper's authors used an IK solver: to find a
// robot configuration for a desired sensor pose under the nominal model.
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <vector>

#include "core/model/robot_model.h"
#include "core/sim/random.h"

namespace selfcal::sim {

struct IkOptions {
  int restarts = 40;
  int iterations = 150;
  double position_tolerance = 1e-4;  // m
  double angle_tolerance = 1e-3;     // rad
  double limit_margin = 0.05;        // rad (or m) kept from every joint limit
};

// Joint positions with ForwardKinematics(model, q) == T_base_sensor within tolerance, or none.
// The first attempt starts at `seed` when given; the others at random configurations.
std::optional<std::vector<double>> SolveIk(const RobotModel& model,
                                           const Eigen::Isometry3d& T_base_sensor,
                                           const std::vector<double>& seed, Random& random,
                                           const IkOptions& options = {});

// A configuration uniformly within the limits shrunk by `margin`.
std::vector<double> RandomConfiguration(const RobotModel& model, double margin, Random& random);

// The orientation error vector (axis * angle, base frame) of R_goal relative to R.
Eigen::Vector3d RotationError(const Eigen::Matrix3d& R_goal, const Eigen::Matrix3d& R);

}  // namespace selfcal::sim
