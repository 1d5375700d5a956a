// Forward kinematics of the MCPC model, templated on the scalar so Ceres can differentiate it.
#pragma once

#include <Eigen/Geometry>
#include <span>

#include "core/model/robot_model.h"

namespace selfcal {

template <typename T>
using Transform3 = Eigen::Transform<T, 3, Eigen::Isometry>;

template <typename T>
Transform3<T> RotX(const T& angle) {
  return Transform3<T>(Eigen::AngleAxis<T>(angle, Eigen::Matrix<T, 3, 1>::UnitX()));
}
template <typename T>
Transform3<T> RotY(const T& angle) {
  return Transform3<T>(Eigen::AngleAxis<T>(angle, Eigen::Matrix<T, 3, 1>::UnitY()));
}
template <typename T>
Transform3<T> RotZ(const T& angle) {
  return Transform3<T>(Eigen::AngleAxis<T>(angle, Eigen::Matrix<T, 3, 1>::UnitZ()));
}
template <typename T>
Transform3<T> Trans(const T& x, const T& y, const T& z) {
  Transform3<T> t = Transform3<T>::Identity();
  t.translation() << x, y, z;
  return t;
}

// st(s) with six parameters p = (alpha, beta, gamma, x, y, z).
template <typename T>
Transform3<T> FullTransform(const T* p) {
  return RotX(p[0]) * RotY(p[1]) * RotZ(p[2]) * Trans(p[3], p[4], p[5]);
}

// st(s) between joints, p = (alpha, beta, x, y).
template <typename T>
Transform3<T> SegmentTransform(const T* p) {
  return RotX(p[0]) * RotY(p[1]) * Trans(p[2], p[3], T(0));
}

// jt(j): rot_z for revolute joints, trans(0, 0, j) for prismatic ones.
template <typename T, typename J>
Transform3<T> JointTransform(JointType type, const J& position) {
  if (type == JointType::kRevolute) return RotZ(T(position));
  return Trans(T(0), T(0), T(position));
}

// T_base_sensor = tr(k, j) for the flat parameters k (layout of robot_model.h) and joint positions.
// `joint_types` has one entry per joint; `parameters` has 12 + 4 (n - 1) entries.
template <typename T, typename J>
Transform3<T> ForwardKinematics(std::span<const JointType> joint_types, const T* parameters,
                                const J* joint_positions) {
  const std::size_t n = joint_types.size();
  Transform3<T> result = FullTransform(parameters + kBaseOffset);
  for (std::size_t i = 0; i < n; ++i) {
    result = result * JointTransform<T>(joint_types[i], joint_positions[i]);
    if (i + 1 < n) result = result * SegmentTransform(parameters + SegmentOffset(i));
  }
  return result * FullTransform(parameters + ToolOffset(n));
}

// Convenience for double models.
std::vector<JointType> JointTypes(const RobotModel& model);
Transform3<double> ForwardKinematics(const RobotModel& model, std::span<const double> joints);

}  // namespace selfcal
