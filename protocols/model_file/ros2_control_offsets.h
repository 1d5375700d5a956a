// Joint zero offsets as a ROS 2 parameter file in the style ros2_control hardware interfaces read
// (`/**: ros__parameters:` then one entry per joint), for controllers that keep their nominal
// kinematics and take the calibration as offsets (core/model/joint_offsets.h). docs/formats.md,
// "Joint offsets".
#pragma once

#include <string>

#include "core/model/joint_offsets.h"
#include "core/model/robot_model.h"
#include "core/util/expected.h"

namespace selfcal {

// The file's text: joint names of `model`, offsets [rad or m] with round-trip precision, and as
// comments degrees, the mount change and the fit's residual; `source` names the calibrated
// model in the header comment.
std::string FormatRos2ControlOffsets(const RobotModel& model, const JointOffsetFit& fit,
                                     const std::string& source);

// FormatRos2ControlOffsets, written atomically.
Status WriteRos2ControlOffsetsFile(const std::string& path, const RobotModel& model,
                                   const JointOffsetFit& fit, const std::string& source);

}  // namespace selfcal
