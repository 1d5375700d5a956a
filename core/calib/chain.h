// The kinematic chain as the engine evaluates it: joint types, the normalization scale s and the
// joint-space correction beyond MCPC (joint_correction.h; empty = the paper's rigid chain).
// All engine stages work in normalized units (the paper's "Normalization",
// core/model/normalization.h): translations of k, points and prismatic joint positions divided
// by s. Poses and their Jacobians come from core/model (kinematics.h, jacobian.h).
#pragma once

#include <algorithm>
#include <cstddef>
#include <span>
#include <vector>

#include "core/calib/dataset.h"
#include "core/calib/joint_correction.h"
#include "core/model/jacobian.h"
#include "core/model/kinematics.h"
#include "core/model/normalization.h"

namespace selfcal::calib {

struct Chain {
  std::vector<JointType> joint_types;
  double scale = 1.0;  // s [m]
  bool has_prismatic = false;
  // Parameters beyond MCPC: k_hat holds ParameterCount() MCPC entries, then correction.Count().
  JointCorrection correction = {};

  std::size_t JointCount() const { return joint_types.size(); }
  std::size_t ParameterCount() const { return ParameterCountOf(joint_types.size()); }
  std::size_t TotalParameterCount() const { return ParameterCount() + correction.Count(); }

  // Joint positions of one pose with prismatic joints divided by s; `buffer` holds JointCount().
  const double* NormalizedJoints(const double* joints, double* buffer) const {
    if (!has_prismatic) return joints;
    std::copy(joints, joints + joint_types.size(), buffer);
    NormalizeJointPositions(std::span<double>(buffer, joint_types.size()), joint_types, scale);
    return buffer;
  }
  // The joints the MCPC chain sees (q + G(q) theta_hat, normalized); `buffer` holds 2 JointCount().
  const double* EffectiveJoints(const double* k_hat, const double* joints, double* buffer,
                                double* columns = nullptr) const {
    if (correction.Empty()) return NormalizedJoints(joints, buffer);
    double* corrected = buffer + joint_types.size();
    correction.Apply(joint_types, joints, k_hat + ParameterCount(), corrected, columns);
    return NormalizedJoints(corrected, buffer);
  }
  // T_base_sensor in normalized units for normalized parameters `k_hat` and raw joints.
  Transform3<double> Pose(const double* k_hat, const double* joints) const {
    double buffer[64];
    return ForwardKinematics<double, double>(joint_types, k_hat,
                                             EffectiveJoints(k_hat, joints, buffer));
  }
  // The same with its 6 x TotalParameterCount() derivative in the normalized parameters (rows:
  // d p, omega in the base frame; core/model/jacobian.h); a correction's column is G_c times the
  // derivative by its joint.
  void PoseWithJacobian(const double* k_hat, const double* joints, Transform3<double>& pose,
                        PoseJacobian& jacobian) const {
    double buffer[64], columns[32];
    const double* q = EffectiveJoints(k_hat, joints, buffer, columns);
    const std::span<const double> k(k_hat, ParameterCount());
    const std::span<const double> q_span(q, JointCount());
    if (correction.Empty()) {
      pose = ForwardKinematicsWithJacobian(joint_types, k, q_span, &jacobian);
      return;
    }
    PoseJacobian parameter_jacobian, joint_jacobian;
    pose =
        ForwardKinematicsWithJacobian(joint_types, k, q_span, &parameter_jacobian, &joint_jacobian);
    jacobian.resize(6, static_cast<long>(TotalParameterCount()));
    jacobian.leftCols(static_cast<long>(ParameterCount())) = parameter_jacobian;
    for (std::size_t c = 0; c < correction.Count(); ++c) {
      jacobian.col(static_cast<long>(ParameterCount() + c)) =
          columns[c] * joint_jacobian.col(static_cast<long>(correction.joints[c]));
    }
  }
};

// A sensor-frame point of a dataset in normalized units, in double.
inline Eigen::Vector3d NormalizedSensorPoint(const Dataset& dataset, std::size_t point,
                                             double scale) {
  return Eigen::Vector3d(dataset.x[point], dataset.y[point], dataset.z[point]) / scale;
}

}  // namespace selfcal::calib
