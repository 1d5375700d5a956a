#include "protocols/trajectory/trajectory_message.h"

namespace selfcal {

selfcal::joint_trajectory_t ToMessage(const trajectory::JointTrajectory& trajectory,
                                      const std::vector<std::string>& joint_names,
                                      const std::string& trajectory_id, std::int64_t utime) {
  selfcal::joint_trajectory_t message;
  message.utime = utime;
  message.trajectory_id = trajectory_id;
  const auto n = trajectory.joint_count();
  message.num_joints = static_cast<std::int32_t>(n);
  message.joint_names = joint_names;
  message.joint_names.resize(n);
  message.num_points = static_cast<std::int32_t>(trajectory.knots().size());
  for (const auto& knot : trajectory.knots()) {
    message.time_from_start.push_back(knot.time);
    message.positions.emplace_back(knot.position.data(), knot.position.data() + n);
    message.velocities.emplace_back(knot.velocity.data(), knot.velocity.data() + n);
  }
  message.valid_until = 0;  // unsigned: SignTrajectory sets both
  message.tag_length = 0;
  return message;
}

Expected<trajectory::JointTrajectory> FromMessage(const selfcal::joint_trajectory_t& message,
                                                  const std::vector<std::string>& joint_names) {
  const std::string where = "joint_trajectory_t '" + message.trajectory_id + "': ";
  if (message.num_joints <= 0 || message.num_points <= 0) {
    return Error{where + "num_joints and num_points must be positive"};
  }
  const auto n = static_cast<std::size_t>(message.num_joints);
  const auto m = static_cast<std::size_t>(message.num_points);
  if (message.joint_names.size() != n || message.time_from_start.size() != m ||
      message.positions.size() != m || message.velocities.size() != m) {
    return Error{where + "array sizes do not match num_joints / num_points"};
  }
  if (!joint_names.empty()) {
    if (joint_names.size() != n) {
      return Error{where + "has " + std::to_string(n) + " joints, the robot " +
                   std::to_string(joint_names.size())};
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (message.joint_names[i] != joint_names[i]) {
        return Error{where + "joint_names[" + std::to_string(i) + "] is '" +
                     message.joint_names[i] + "', the robot's joint is '" + joint_names[i] + "'"};
      }
    }
  }
  std::vector<trajectory::Knot> knots(m);
  for (std::size_t k = 0; k < m; ++k) {
    if (message.positions[k].size() != n || message.velocities[k].size() != n) {
      return Error{where + "positions/velocities[" + std::to_string(k) + "] has the wrong size"};
    }
    knots[k].time = message.time_from_start[k];
    knots[k].position = Eigen::Map<const Eigen::VectorXd>(message.positions[k].data(),
                                                          static_cast<Eigen::Index>(n));
    knots[k].velocity = Eigen::Map<const Eigen::VectorXd>(message.velocities[k].data(),
                                                          static_cast<Eigen::Index>(n));
  }
  auto trajectory = trajectory::JointTrajectory::FromKnots(std::move(knots));
  if (!trajectory.ok()) return Error{where + trajectory.error().message};
  return trajectory;
}

}  // namespace selfcal
