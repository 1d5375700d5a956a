// selfcal.joint_trajectory_t <-> core/trajectory's JointTrajectory. The daemon builds
// messages with ToMessage; the driver checks and converts them with FromMessage.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/trajectory/joint_trajectory.h"
#include "core/util/expected.h"
#include "selfcal/joint_trajectory_t.hpp"

namespace selfcal {

// Unsigned (tag_length 0, valid_until 0): SignTrajectory signs it.
selfcal::joint_trajectory_t ToMessage(const trajectory::JointTrajectory& trajectory,
                                      const std::vector<std::string>& joint_names,
                                      const std::string& trajectory_id, std::int64_t utime);

// Checks shapes (num_points rows of num_joints values), names (when `joint_names` is not empty:
// same count, same order) and knots (JointTrajectory::FromKnots). Errors name the field.
// An empty trajectory (num_points = 0) is a stop request, not decoded here: check it first.
Expected<trajectory::JointTrajectory> FromMessage(const selfcal::joint_trajectory_t& message,
                                                  const std::vector<std::string>& joint_names);

}  // namespace selfcal
