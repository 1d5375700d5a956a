// T_base_sensor = tr(k, j) together with its derivative with respect to every flat parameter of
// k, as spatial twists in the base frame: column l is (v_l, omega_l) with
//   d(T p) / d k_l = omega_l x (T p) + v_l    for any sensor-frame point p.
// This is the per-pose 6 x K Jacobian of issue 5: all points measured in one pose share it, so a
// residual's derivative is a 6-vector dotted with this matrix instead of a walk along the chain.
// Checked against automatic differentiation of core/model's templated ForwardKinematics in
// tests/calib/pose_jacobian_test.cc.
#pragma once

#include <Eigen/Core>
#include <span>

#include "core/model/kinematics.h"

namespace selfcal::calib {

using PoseJacobian = Eigen::Matrix<double, 6, Eigen::Dynamic>;

// Walks the chain once. `parameters` has the flat layout of core/model/robot_model.h;
// `jacobian` is resized to 6 x (12 + 4 (n - 1)). Rows 0..2 are v, rows 3..5 are omega.
void ForwardKinematicsWithJacobian(std::span<const JointType> joint_types, const double* parameters,
                                   const double* joint_positions, Transform3<double>& T_base_sensor,
                                   PoseJacobian& jacobian);

}  // namespace selfcal::calib
