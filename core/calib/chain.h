// The kinematic chain as the engine evaluates it: joint types, the normalization scale s and the
// joint-space correction beyond MCPC (joint_correction.h; empty = the paper's rigid chain), and
// the sensor intrinsics calibrated with them (sensor_intrinsics.h), which move no pose.
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
#include "core/calib/sensor_intrinsics.h"
#include "core/model/jacobian.h"
#include "core/model/kinematics.h"
#include "core/model/normalization.h"

namespace selfcal::calib {

struct Chain {
  std::vector<JointType> joint_types;
  double scale = 1.0;  // s [m]
  bool has_prismatic = false;
  // Parameters beyond MCPC: k_hat holds ParameterCount() MCPC entries, then correction.Count(),
  // then intrinsics.Count().
  JointCorrection correction = {};
  SensorIntrinsics intrinsics = {};
  // The links' radius, normalized (RobotModel::link_radius / s); 0 = not given.
  double link_radius = 0;

  std::size_t JointCount() const { return joint_types.size(); }
  std::size_t ParameterCount() const { return ParameterCountOf(joint_types.size()); }
  std::size_t FirstIntrinsic() const { return ParameterCount() + correction.Count(); }
  std::size_t TotalParameterCount() const { return FirstIntrinsic() + intrinsics.Count(); }
  // The intrinsics' free values in `k_hat` (sensor_intrinsics.h), normalized.
  std::span<const double> FreeIntrinsics(const double* k_hat) const {
    return {k_hat + FirstIntrinsic(), intrinsics.Count()};
  }

  // Joint positions of one pose with prismatic joints divided by s; `buffer` holds JointCount().
  const double* NormalizedJoints(const double* joints, double* buffer) const {
    if (!has_prismatic) return joints;
    std::copy(joints, joints + joint_types.size(), buffer);
    NormalizeJointPositions(std::span<double>(buffer, joint_types.size()), joint_types, scale);
    return buffer;
  }
  // The joints the MCPC chain sees (q + G (theta_hat - theta_0), normalized); `buffer` holds
  // 2 JointCount(). When `G` is not null it receives G (joint_correction.h) by the normalized
  // joints: a prismatic joint's row divided by s.
  const double* EffectiveJoints(const double* k_hat, const PoseState& state, double* buffer,
                                double* G = nullptr) const {
    if (correction.Empty()) return NormalizedJoints(state.q, buffer);
    const std::size_t n = joint_types.size();
    double* corrected = buffer + n;
    correction.Apply(joint_types, state, k_hat + ParameterCount(), corrected, G);
    if (G != nullptr && has_prismatic) {
      for (std::size_t j = 0; j < n; ++j) {
        if (joint_types[j] != JointType::kPrismatic) continue;
        for (std::size_t c = 0; c < correction.Count(); ++c) G[c * n + j] /= scale;
      }
    }
    return NormalizedJoints(corrected, buffer);
  }
  // T_base_sensor in normalized units for normalized parameters `k_hat` and a raw joint state.
  Transform3<double> Pose(const double* k_hat, const PoseState& state) const {
    double buffer[64];
    return ForwardKinematics<double, double>(joint_types, k_hat,
                                             EffectiveJoints(k_hat, state, buffer));
  }
  Transform3<double> Pose(const double* k_hat, const double* joints) const {
    return Pose(k_hat, PoseState{joints});
  }
  // The same with its 6 x TotalParameterCount() derivative in the normalized parameters (rows:
  // d p, omega in the base frame; core/model/jacobian.h); a correction's column is the joints'
  // Jacobian times G_c, an intrinsic's column is 0.
  void PoseWithJacobian(const double* k_hat, const PoseState& state, Transform3<double>& pose,
                        PoseJacobian& jacobian) const {
    double buffer[64], G[kMaxCorrectionColumns * 32];
    const double* q = EffectiveJoints(k_hat, state, buffer, G);
    const std::span<const double> k(k_hat, ParameterCount());
    const std::span<const double> q_span(q, JointCount());
    if (correction.Empty()) {
      pose = ForwardKinematicsWithJacobian(joint_types, k, q_span, &jacobian);
      if (!intrinsics.Empty()) {
        jacobian.conservativeResize(6, static_cast<long>(TotalParameterCount()));
        jacobian.rightCols(static_cast<long>(intrinsics.Count())).setZero();
      }
      return;
    }
    PoseJacobian parameter_jacobian, joint_jacobian;
    pose =
        ForwardKinematicsWithJacobian(joint_types, k, q_span, &parameter_jacobian, &joint_jacobian);
    jacobian.setZero(6, static_cast<long>(TotalParameterCount()));
    jacobian.leftCols(static_cast<long>(ParameterCount())) = parameter_jacobian;
    const long n = static_cast<long>(JointCount());
    for (std::size_t c = 0; c < correction.Count(); ++c) {
      jacobian.col(static_cast<long>(ParameterCount() + c)).noalias() =
          joint_jacobian * Eigen::Map<const Eigen::VectorXd>(G + static_cast<long>(c) * n, n);
    }
  }
  void PoseWithJacobian(const double* k_hat, const double* joints, Transform3<double>& pose,
                        PoseJacobian& jacobian) const {
    PoseWithJacobian(k_hat, PoseState{joints}, pose, jacobian);
  }
};

// The rigid MCPC chain of `model` at the normalization scale `scale`.
inline Chain ChainOf(const RobotModel& model, double scale) {
  Chain chain{JointTypes(model), scale, false};
  for (JointType type : chain.joint_types) chain.has_prismatic |= type == JointType::kPrismatic;
  chain.link_radius = model.link_radius / scale;
  return chain;
}

// A sensor-frame point of a dataset in normalized units, in double.
inline Eigen::Vector3d NormalizedSensorPoint(const Dataset& dataset, std::size_t point,
                                             double scale) {
  return Eigen::Vector3d(dataset.x[point], dataset.y[point], dataset.z[point]) / scale;
}

}  // namespace selfcal::calib
