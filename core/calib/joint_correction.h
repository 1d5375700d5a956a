// Engine parameters beyond MCPC that act in joint space (docs/engine.md, deviation 15):
//   q_eff = q + G(q) theta_hat,
// with theta_hat appended to the normalized MCPC parameters k_hat (column c of G is flat
// parameter K + c). The pose's derivative by theta_hat_c is G_c times its derivative by the
// joints (the joint's twist, core/model/jacobian.h), so the fast solver, the rigid-pair
// reduction and the moving matches through knots take the extra columns like any parameter.
//
// Joint elasticity fills it: column c acts on joint joints[c] alone,
//   G_{joints[c], c}(q) = tau_j(q) / reference_torque[c],
// tau the gravity torque of core/model/gravity.h at `frozen_parameters` (the estimate at the
// start of the ICP iteration, held fixed during one Levenberg-Marquardt solve as the normals
// are). So theta_hat_c = compliance * reference_torque[c] is the joint's deflection in rad at the
// largest gravity torque the fit scans give it: O(1e-3) for a stiff arm, and a step of the
// epsilon stop criterion compares rad with rad like the angles of k_hat. A sensor latency
// (issue 16, item 3: G = the joint velocity, one column per recording) would add columns here.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "core/model/robot_model.h"

namespace selfcal::calib {

struct JointCorrection {
  std::vector<std::size_t> joints;        // the joint each column acts on
  std::vector<double> reference_torque;   // Nm per column (theta_hat = compliance * this)
  GravityLoad load;                       // the masses of the gravity torque
  std::vector<double> frozen_parameters;  // flat MCPC parameters (SI) where tau is evaluated

  std::size_t Count() const { return joints.size(); }
  bool Empty() const { return joints.empty(); }

  // q_eff = q + G(q) theta_hat for raw joint positions `q` (n entries) into `q_eff`; when
  // `columns` is not null, columns[c] = G_{joints[c], c}(q) (the only non-zero of column c).
  void Apply(std::span<const JointType> joint_types, const double* q, const double* theta_hat,
             double* q_eff, double* columns) const;
};

// Joint elasticity for `model` (its gravity load) over the poses `configurations` (n joint
// positions each, raw units): the revolute joints whose largest gravity torque over them, at the
// model's parameters, reaches kMinTorqueShare of the largest joint's (A1 of an upright arm has
// none: its compliance would be unobservable), with that torque as their reference.
inline constexpr double kMinTorqueShare = 0.005;
JointCorrection ElasticityCorrection(const RobotModel& model,
                                     const std::vector<const double*>& configurations);

}  // namespace selfcal::calib
