// Mounting a sensor on the flange: the nominal tool st(s_n) of the robot file (last joint to
// flange) composed with the sensor mount T_flange_sensor, written back in MCPC's tool form
// rot_x(alpha) * rot_y(beta) * rot_z(gamma) * trans(x, y, z).
#pragma once

#include <Eigen/Geometry>

#include "core/model/robot_model.h"

namespace selfcal::sim {

// T_flange_sensor = trans(x, y, z) * rot_z(yaw) * rot_y(pitch) * rot_x(roll) (URDF's rpy).
struct SensorMount {
  double x = 0, y = 0, z = 0;           // m
  double roll = 0, pitch = 0, yaw = 0;  // rad
  Eigen::Isometry3d Transform() const;
};

// `robot` with its tool replaced by tool * mount.
RobotModel WithSensorMount(const RobotModel& robot, const SensorMount& mount);

}  // namespace selfcal::sim
