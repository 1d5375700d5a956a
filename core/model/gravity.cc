#include "core/model/gravity.h"

#include "core/model/kinematics.h"

namespace selfcal {

JointFrames ComputeJointFrames(std::span<const JointType> joint_types, const double* parameters,
                               const double* joint_positions) {
  const std::size_t n = joint_types.size();
  JointFrames frames;
  Transform3<double> pose = FullTransform(parameters + kBaseOffset);
  for (std::size_t i = 0; i < n; ++i) {
    pose = pose * JointTransform<double>(joint_types[i], joint_positions[i]);
    frames.axes.push_back(pose.linear().col(2));
    frames.origins.push_back(pose.translation());
    if (i + 1 < n) pose = pose * SegmentTransform(parameters + SegmentOffset(i));
  }
  frames.tool_point = (pose * FullTransform(parameters + ToolOffset(n))).translation();
  return frames;
}

std::vector<double> GravityTorques(std::span<const double> link_masses, double sensor_mass,
                                   const JointFrames& frames) {
  const std::vector<Eigen::Vector3d>& axes = frames.axes;
  const std::vector<Eigen::Vector3d>& origins = frames.origins;
  const Eigen::Vector3d& tool_point = frames.tool_point;
  const std::size_t n = axes.size();
  // Mass points: link i between its origin and the next origin that differs from it.
  std::vector<Eigen::Vector3d> centres(n);
  for (std::size_t i = 0; i < n; ++i) {
    Eigen::Vector3d next = tool_point;
    for (std::size_t k = i + 1; k < n; ++k) {
      if ((origins[k] - origins[i]).norm() > 1e-6) {
        next = origins[k];
        break;
      }
    }
    centres[i] = 0.5 * (origins[i] + next);
  }
  const Eigen::Vector3d gravity(0, 0, -9.81);
  std::vector<double> torque(n, 0.0);
  for (std::size_t j = 0; j < n; ++j) {
    Eigen::Vector3d moment = (tool_point - origins[j]).cross(sensor_mass * gravity);
    for (std::size_t i = j; i < n; ++i) {
      moment += (centres[i] - origins[j]).cross(link_masses[i] * gravity);
    }
    torque[j] = axes[j].dot(moment);
  }
  return torque;
}

std::vector<double> GravityTorques(const GravityLoad& load, const JointFrames& frames) {
  return GravityTorques(load.link_masses, load.sensor_mass, frames);
}

}  // namespace selfcal
