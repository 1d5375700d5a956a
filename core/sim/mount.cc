#include "core/sim/mount.h"

#include "core/model/chain.h"

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

RobotModel WithSensorMount(const RobotModel& robot, const SensorMount& mount) {
  RobotModel mounted = robot;
  mounted.tool = ToFullTransformParams(FromFullTransformParams(robot.tool) * mount.Transform());
  return mounted;
}

}  // namespace selfcal::sim
