#include "core/model/jacobian.h"

#include <cmath>
#include <cstdlib>
#include <iostream>

namespace selfcal {
namespace {

// The running frame of the forward pass: axes R and origin p of the frame before the next factor.
struct Frame {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
};

// Records the column of a rotation factor about local axis `axis` (0 = x, 1 = y, 2 = z) and
// applies it. Rows 0..2 temporarily hold the frame origin; Finish() turns them into d p / d k.
void RotateAbout(int axis, double angle, Frame& frame, double* column) {
  if (column != nullptr) {
    Eigen::Map<Eigen::Vector3d> origin(column), omega(column + 3);
    origin = frame.p;
    omega = frame.R.col(axis);
  }
  const double c = std::cos(angle);
  const double s = std::sin(angle);
  // R * rot_axis(angle) only mixes the two other columns.
  const int a = (axis + 1) % 3;
  const int b = (axis + 2) % 3;
  const Eigen::Vector3d col_a = frame.R.col(a);
  const Eigen::Vector3d col_b = frame.R.col(b);
  frame.R.col(a) = c * col_a + s * col_b;
  frame.R.col(b) = -s * col_a + c * col_b;
}

// Records the column of a translation factor along local axis `axis` (d p / d k = R_F e,
// omega = 0) and applies it.
void TranslateAlong(int axis, double distance, Frame& frame, double* column) {
  if (column != nullptr) {
    Eigen::Map<Eigen::Vector3d> velocity(column), omega(column + 3);
    velocity = frame.R.col(axis);
    omega.setZero();
  }
  frame.p += distance * frame.R.col(axis);
}

void CheckSizes(std::size_t joints, std::size_t parameters, std::size_t positions) {
  if (joints == 0 || parameters != ParameterCountOf(joints) || positions != joints) {
    std::cerr << "selfcal: ForwardKinematicsWithJacobian: " << joints << " joints, " << parameters
              << " parameters, " << positions << " joint positions\n";
    std::abort();
  }
}

}  // namespace

Eigen::Isometry3d ForwardKinematicsWithJacobian(std::span<const JointType> joint_types,
                                                std::span<const double> parameters,
                                                std::span<const double> joint_positions,
                                                PoseJacobian* parameter_jacobian,
                                                PoseJacobian* joint_jacobian) {
  const std::size_t n = joint_types.size();
  CheckSizes(n, parameters.size(), joint_positions.size());
  const auto k_count = static_cast<Eigen::Index>(parameters.size());
  if (parameter_jacobian != nullptr) parameter_jacobian->resize(6, k_count);
  if (joint_jacobian != nullptr) joint_jacobian->resize(6, static_cast<Eigen::Index>(n));

  auto param_column = [&](std::size_t index) -> double* {
    return parameter_jacobian != nullptr
               ? parameter_jacobian->col(static_cast<Eigen::Index>(index)).data()
               : nullptr;
  };
  auto joint_column = [&](std::size_t index) -> double* {
    return joint_jacobian != nullptr ? joint_jacobian->col(static_cast<Eigen::Index>(index)).data()
                                     : nullptr;
  };

  Frame frame;
  // st() with six parameters at `offset`.
  auto full = [&](std::size_t offset) {
    for (int axis = 0; axis < 3; ++axis) {
      RotateAbout(axis, parameters[offset + static_cast<std::size_t>(axis)], frame,
                  param_column(offset + static_cast<std::size_t>(axis)));
    }
    // trans(x, y, z) after the rotations: all three along the same final axes.
    for (int axis = 0; axis < 3; ++axis) {
      const std::size_t index = offset + 3 + static_cast<std::size_t>(axis);
      TranslateAlong(axis, parameters[index], frame, param_column(index));
    }
  };

  full(kBaseOffset);
  for (std::size_t i = 0; i < n; ++i) {
    if (joint_types[i] == JointType::kRevolute) {
      RotateAbout(2, joint_positions[i], frame, joint_column(i));
    } else {
      TranslateAlong(2, joint_positions[i], frame, joint_column(i));
    }
    if (i + 1 < n) {
      const std::size_t o = SegmentOffset(i);
      RotateAbout(0, parameters[o], frame, param_column(o));
      RotateAbout(1, parameters[o + 1], frame, param_column(o + 1));
      TranslateAlong(0, parameters[o + 2], frame, param_column(o + 2));
      TranslateAlong(1, parameters[o + 3], frame, param_column(o + 3));
    }
  }
  full(ToolOffset(n));

  // Rotation columns: rows 0..2 hold the origin o_F; d p / d k = omega x (p - o_F).
  auto finish = [&](PoseJacobian& jacobian, Eigen::Index c) {
    const Eigen::Vector3d omega = jacobian.block<3, 1>(3, c);
    const Eigen::Vector3d lever = frame.p - jacobian.block<3, 1>(0, c);
    jacobian.block<3, 1>(0, c) = omega.cross(lever);
  };
  if (parameter_jacobian != nullptr) {
    for (std::size_t i = 0; i < parameters.size(); ++i) {
      if (!IsTranslationIndex(i, n)) finish(*parameter_jacobian, static_cast<Eigen::Index>(i));
    }
  }
  if (joint_jacobian != nullptr) {
    for (std::size_t i = 0; i < n; ++i) {
      if (joint_types[i] == JointType::kRevolute) {
        finish(*joint_jacobian, static_cast<Eigen::Index>(i));
      }
    }
  }

  Eigen::Isometry3d T_base_sensor = Eigen::Isometry3d::Identity();
  T_base_sensor.linear() = frame.R;
  T_base_sensor.translation() = frame.p;
  return T_base_sensor;
}

void ChainPointJacobianRotated(const PoseJacobian& pose_jacobian, const Eigen::Vector3d& r,
                               Eigen::Ref<PointJacobian> out) {
  // omega x r = -(r x omega): written out to avoid building the skew matrix per column.
  const Eigen::Index cols = pose_jacobian.cols();
  for (Eigen::Index c = 0; c < cols; ++c) {
    const double wx = pose_jacobian(3, c), wy = pose_jacobian(4, c), wz = pose_jacobian(5, c);
    out(0, c) = pose_jacobian(0, c) + wy * r.z() - wz * r.y();
    out(1, c) = pose_jacobian(1, c) + wz * r.x() - wx * r.z();
    out(2, c) = pose_jacobian(2, c) + wx * r.y() - wy * r.x();
  }
}

void ChainPointJacobian(const PoseJacobian& pose_jacobian, const Eigen::Isometry3d& T_base_sensor,
                        const Eigen::Vector3d& p_sensor, PointJacobian* out) {
  out->resize(3, pose_jacobian.cols());
  ChainPointJacobianRotated(pose_jacobian, T_base_sensor.linear() * p_sensor, *out);
}

}  // namespace selfcal
