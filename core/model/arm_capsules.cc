#include "core/model/arm_capsules.h"

#include <algorithm>

namespace selfcal {

double Capsule::AxisDistance(const Eigen::Vector3d& point) const {
  const Eigen::Vector3d axis = b - a;
  const double length_squared = axis.squaredNorm();
  const double t =
      length_squared > 0 ? std::clamp((point - a).dot(axis) / length_squared, 0.0, 1.0) : 0.0;
  return (point - (a + t * axis)).norm();
}

std::vector<Capsule> ArmCapsules(const JointFrames& frames, double radius) {
  std::vector<Capsule> capsules;
  Eigen::Vector3d last = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> points = frames.origins;
  points.push_back(frames.tool_point);
  for (const auto& point : points) {
    if ((point - last).norm() < 1e-6) continue;
    capsules.push_back({last, point, radius});
    last = point;
  }
  return capsules;
}

}  // namespace selfcal
