// The kinematic chain as the engine evaluates it: joint types and the normalization scale s.
// All engine stages work in normalized units (the paper's "Normalization"): translations of k,
// points and prismatic joint positions divided by s.
#pragma once

#include <cstddef>
#include <vector>

#include "core/calib/dataset.h"
#include "core/calib/pose_jacobian.h"
#include "core/model/kinematics.h"

namespace selfcal::calib {

struct Chain {
  std::vector<JointType> joint_types;
  double scale = 1.0;  // s [m]
  bool has_prismatic = false;

  std::size_t JointCount() const { return joint_types.size(); }
  std::size_t ParameterCount() const { return 12 + 4 * (joint_types.size() - 1); }

  // Joint positions of one pose with prismatic joints divided by s; `buffer` holds JointCount().
  const double* NormalizedJoints(const double* joints, double* buffer) const {
    if (!has_prismatic) return joints;
    for (std::size_t i = 0; i < joint_types.size(); ++i) {
      buffer[i] = joint_types[i] == JointType::kPrismatic ? joints[i] / scale : joints[i];
    }
    return buffer;
  }
  // T_base_sensor in normalized units for normalized parameters `k_hat` and raw joints.
  Transform3<double> Pose(const double* k_hat, const double* joints) const {
    double buffer[64];
    return ForwardKinematics<double, double>(joint_types, k_hat, NormalizedJoints(joints, buffer));
  }
  void PoseWithJacobian(const double* k_hat, const double* joints, Transform3<double>& pose,
                        PoseJacobian& jacobian) const {
    double buffer[64];
    ForwardKinematicsWithJacobian(joint_types, k_hat, NormalizedJoints(joints, buffer), pose,
                                  jacobian);
  }
};

// A sensor-frame point of a dataset in normalized units, in double.
inline Eigen::Vector3d NormalizedSensorPoint(const Dataset& dataset, std::size_t point,
                                             double scale) {
  return Eigen::Vector3d(dataset.x[point], dataset.y[point], dataset.z[point]) / scale;
}

}  // namespace selfcal::calib
