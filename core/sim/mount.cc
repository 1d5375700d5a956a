#include "core/sim/mount.h"

#include <algorithm>
#include <cmath>

#include "core/model/kinematics.h"

namespace selfcal::sim {

Eigen::Isometry3d SensorMount::Transform() const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(x, y, z);
  T.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  return T;
}

FullTransformParams ToFullTransformParams(const Eigen::Isometry3d& T) {
  // R = Rx(a) Ry(b) Rz(c): R02 = sin b, R12 = -sin a cos b, R22 = cos a cos b,
  // R01 = -cos b sin c, R00 = cos b cos c.
  const Eigen::Matrix3d R = T.linear();
  FullTransformParams p;
  p.beta = std::asin(std::clamp(R(0, 2), -1.0, 1.0));
  p.alpha = std::atan2(-R(1, 2), R(2, 2));
  p.gamma = std::atan2(-R(0, 1), R(0, 0));
  const Eigen::Vector3d local = R.transpose() * T.translation();  // trans() comes after rot()
  p.x = local.x();
  p.y = local.y();
  p.z = local.z();
  return p;
}

Eigen::Isometry3d FromFullTransformParams(const FullTransformParams& p) {
  const double values[6] = {p.alpha, p.beta, p.gamma, p.x, p.y, p.z};
  return FullTransform(values);
}

RobotModel WithSensorMount(const RobotModel& robot, const SensorMount& mount) {
  RobotModel mounted = robot;
  mounted.tool = ToFullTransformParams(FromFullTransformParams(robot.tool) * mount.Transform());
  return mounted;
}

}  // namespace selfcal::sim
