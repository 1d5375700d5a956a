// The gravity load of an arm: the one home of the point-mass gravity model that the simulator's
// joint elasticity (core/sim/field_effects.h, JointElasticityEffect) and the engine's compliance
// parameters (core/calib/joint_correction.h, docs/engine.md deviation 15) both use.
//
// Point masses: link i (the body joint i turns) at the middle between joint i's origin and the
// next joint origin that differs from it (the tool point for the last links), the sensor at the
// tool point (the sensor frame's origin). Gravity is -z of the base frame, 9.81 m/s^2.
// The torque of joint j is the moment of every mass beyond it about its axis, in Nm: a joint of
// compliance c [rad/Nm] turns by c * tau_j(q).
#pragma once

#include <Eigen/Core>
#include <span>
#include <vector>

#include "core/model/robot_model.h"

namespace selfcal {

// Joint axes and origins of a configuration in the base frame (joint i's frame after its
// motion), and the tool point (the sensor's origin).
struct JointFrames {
  std::vector<Eigen::Vector3d> axes, origins;
  Eigen::Vector3d tool_point = Eigen::Vector3d::Zero();
};
// `parameters`: the flat MCPC parameters (robot_model.h, SI units), `joint_positions` n entries.
JointFrames ComputeJointFrames(std::span<const JointType> joint_types, const double* parameters,
                               const double* joint_positions);

// The gravity torque about every joint's axis [Nm] of the masses beyond it (tau_j in the header
// comment). `link_masses` has one entry per joint of `frames`.
std::vector<double> GravityTorques(std::span<const double> link_masses, double sensor_mass,
                                   const JointFrames& frames);
// The same for a model's gravity load (needs load.link_masses.size() == joint count).
std::vector<double> GravityTorques(const GravityLoad& load, const JointFrames& frames);

}  // namespace selfcal
