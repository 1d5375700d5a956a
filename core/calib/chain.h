// The kinematic chain as the engine evaluates it: joint types and the normalization scale s.
// All engine stages work in normalized units (the paper's "Normalization",
// core/model/normalization.h): translations of k, points and prismatic joint positions divided
// by s. Poses and their Jacobians come from core/model (kinematics.h, jacobian.h).
#pragma once

#include <algorithm>
#include <cstddef>
#include <span>
#include <vector>

#include "core/calib/dataset.h"
#include "core/model/jacobian.h"
#include "core/model/kinematics.h"
#include "core/model/normalization.h"

namespace selfcal::calib {

struct Chain {
  std::vector<JointType> joint_types;
  double scale = 1.0;  // s [m]
  bool has_prismatic = false;

  std::size_t JointCount() const { return joint_types.size(); }
  std::size_t ParameterCount() const { return ParameterCountOf(joint_types.size()); }

  // Joint positions of one pose with prismatic joints divided by s; `buffer` holds JointCount().
  const double* NormalizedJoints(const double* joints, double* buffer) const {
    if (!has_prismatic) return joints;
    std::copy(joints, joints + joint_types.size(), buffer);
    NormalizeJointPositions(std::span<double>(buffer, joint_types.size()), joint_types, scale);
    return buffer;
  }
  // T_base_sensor in normalized units for normalized parameters `k_hat` and raw joints.
  Transform3<double> Pose(const double* k_hat, const double* joints) const {
    double buffer[64];
    return ForwardKinematics<double, double>(joint_types, k_hat, NormalizedJoints(joints, buffer));
  }
  // The same with its 6 x K derivative in the normalized parameters (rows: d p, omega in the
  // base frame; core/model/jacobian.h).
  void PoseWithJacobian(const double* k_hat, const double* joints, Transform3<double>& pose,
                        PoseJacobian& jacobian) const {
    double buffer[64];
    pose = ForwardKinematicsWithJacobian(
        joint_types, std::span<const double>(k_hat, ParameterCount()),
        std::span<const double>(NormalizedJoints(joints, buffer), JointCount()), &jacobian);
  }
};

// A sensor-frame point of a dataset in normalized units, in double.
inline Eigen::Vector3d NormalizedSensorPoint(const Dataset& dataset, std::size_t point,
                                             double scale) {
  return Eigen::Vector3d(dataset.x[point], dataset.y[point], dataset.z[point]) / scale;
}

}  // namespace selfcal::calib
