// Analytic derivatives of the MCPC forward kinematics with respect to the flat parameters k
// (layout of robot_model.h) and the joint positions, in one pass along the chain. The one pose
// Jacobian: the engine takes it per pose through core/calib/chain.h (Chain::PoseWithJacobian).
//
// Convention (docs/kinematics.md, "Derivatives"): for a small change dk of parameter i,
//   p_base_sensor(k + dk) = p + J.block<3,1>(0, i) * dk          (translation of T_base_sensor)
//   R_base_sensor(k + dk) = (I + [J.block<3,1>(3, i) * dk]_x) * R (rotation of T_base_sensor)
// that is, rows 0..2 hold d p / d k_i (m per rad or m per m) and rows 3..5 the angular velocity
// omega_i of the sensor frame expressed in the base frame ("spatial" angular part,
// [omega]_x = dR/dk_i * R^T). Columns follow the flat parameter order, all K of them; the engine
// selects the masked ones.
//
// Every parameter enters exactly one elementary factor of
//   tr(k, j) = st(s_0) jt(j_1) st(s_1) ... jt(j_n) st(s_n),
//   st = rot_x(alpha) rot_y(beta) [rot_z(gamma)] trans(x, y, [z]).
// With F the frame just before that factor (origin o_F, axes R_F) and e its local axis:
//   rotation factor:    omega = R_F e,  d p / d k = omega x (p - o_F)
//   translation factor: omega = 0,      d p / d k = R_F e
// so one forward pass that records R_F e and o_F per factor, followed by one cross product per
// column, gives all K columns: O(K), no per-parameter forward kinematics.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <span>

#include "core/model/robot_model.h"

namespace selfcal {

// 6 x K (parameters) or 6 x n (joints); rows: d p (3), omega in the base frame (3).
using PoseJacobian = Eigen::Matrix<double, 6, Eigen::Dynamic>;
// 3 x K: d p_base / d k of a point fixed in the sensor frame.
using PointJacobian = Eigen::Matrix<double, 3, Eigen::Dynamic>;

// T_base_sensor = tr(k, j) and, when not null, its derivatives with respect to the K flat
// parameters (`parameter_jacobian`, resized to 6 x K) and to the n joint positions
// (`joint_jacobian`, resized to 6 x n; for a revolute joint d/dq in rad, prismatic in m).
// `parameters` has 12 + 4 (n - 1) entries, `joint_positions` n; sizes are checked (abort).
Eigen::Isometry3d ForwardKinematicsWithJacobian(std::span<const JointType> joint_types,
                                                std::span<const double> parameters,
                                                std::span<const double> joint_positions,
                                                PoseJacobian* parameter_jacobian,
                                                PoseJacobian* joint_jacobian = nullptr);

// Derivative of p_base = T_base_sensor * p_sensor with respect to whatever `pose_jacobian`
// differentiates (parameters or joints):
//   d p_base / d k_i = J_p,i + omega_i x (R_base_sensor p_sensor) = J_p,i - [R p_sensor]_x omega_i.
// Chaining per point through the per-pose Jacobian costs 3 x 3 x K multiply-adds per point.
// `out` is resized to 3 x pose_jacobian.cols().
void ChainPointJacobian(const PoseJacobian& pose_jacobian, const Eigen::Isometry3d& T_base_sensor,
                        const Eigen::Vector3d& p_sensor, PointJacobian* out);

// The same, given the point already rotated into base axes (r = R_base_sensor * p_sensor), for
// callers that have it at hand; `out` must already be 3 x pose_jacobian.cols().
void ChainPointJacobianRotated(const PoseJacobian& pose_jacobian, const Eigen::Vector3d& r,
                               Eigen::Ref<PointJacobian> out);

}  // namespace selfcal
