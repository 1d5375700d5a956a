#include "protocols/model_file/ros2_control_offsets.h"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>

#include "core/util/atomic_file.h"
#include "protocols/model_file/yaml_writer.h"

namespace selfcal {

std::string FormatRos2ControlOffsets(const RobotModel& model, const JointOffsetFit& fit,
                                     const std::string& source) {
  const double degrees = 180.0 / std::numbers::pi;
  std::ostringstream out;
  out << "# Joint zero offsets of " << source << " against the nominal kinematics (selfcal).\n"
      << "# A controller with the nominal kinematics adds each offset to the measured joint\n"
      << "# position: nominal(q + offset) = calibrated(q). The last joint's offset cannot be told\n"
      << "# from the sensor mount turning about it and is part of the mount change.\n";
  char line[200];
  std::snprintf(line, sizeof line,
                "# mount change: %.3f mm, %.4f deg; unexplained by offsets and mount: %.3f mm, "
                "%.4f deg RMS over %zu configurations\n",
                fit.mount_shift_m * 1e3, fit.mount_turn_rad * degrees, fit.rms_position_m * 1e3,
                fit.rms_orientation_rad * degrees, fit.samples);
  out << line << "/**:\n  ros__parameters:\n    joint_offsets:\n";
  for (std::size_t i = 0; i < model.JointCount(); ++i) {
    const bool revolute = model.joints[i].type == JointType::kRevolute;
    const double offset = fit.offsets[i] == 0.0 ? 0.0 : fit.offsets[i];  // no "-0"
    out << "      " << yaml::Text(model.joints[i].name) << ": " << yaml::Number(offset) << "  # "
        << (revolute ? std::to_string(offset * degrees) + " deg"
                     : std::to_string(offset * 1e3) + " mm")
        << "\n";
  }
  return out.str();
}

Status WriteRos2ControlOffsetsFile(const std::string& path, const RobotModel& model,
                                   const JointOffsetFit& fit, const std::string& source) {
  return WriteFileAtomically(path, FormatRos2ControlOffsets(model, fit, source));
}

}  // namespace selfcal
