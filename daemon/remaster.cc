#include "daemon/remaster.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>

namespace selfcal::daemon {

Expected<RobotModel> RemasterStart(const RobotModel& installed) {
  auto mask = RemasterMask(installed);
  if (!mask) return mask.error();
  RobotModel start = installed;
  start.mask = std::move(*mask);
  return start;
}

Expected<bool> IsRemastering(const std::string& calibration_yaml) {
  try {
    const YAML::Node calibration = YAML::Load(calibration_yaml);
    return calibration.IsMap() && calibration["remaster"].IsDefined();
  } catch (const YAML::Exception& e) {
    return Error{"calibration: section, line " + std::to_string(e.mark.line + 1) + ": " + e.msg};
  }
}

Expected<RobotModel> JudgedAgainst(const RobotModel& installed,
                                   const std::string& calibration_yaml) {
  auto remastering = IsRemastering(calibration_yaml);
  if (!remastering) return remastering.error();
  if (!*remastering) return installed;
  return RemasterStart(installed);
}

AcceptanceConfig RemasterAcceptance(AcceptanceConfig site) {
  site.min_improvement = 0;
  return site;
}

RemasterCorrections DescribeRemaster(const RobotModel& installed, const RobotModel& calibrated,
                                     const std::string& against) {
  RemasterCorrections out;
  out.fit = FitJointOffsets(installed, calibrated);
  const JointOffsetFit& fit = out.fit;
  out.text = "joint zero offsets against " + against + " (add to the measured position):\n";
  out.yaml =
      "remaster:  # the joints' zero offsets and the sensor mount only (--mode remaster)\n"
      "  joint_offsets:  # against " +
      against + ": add to the measured position\n";
  out.summary = "zero offsets to add to the measured position:";
  char line[200];
  const std::size_t n = installed.JointCount();
  for (std::size_t i = 0; i < n; ++i) {
    const bool revolute = installed.joints[i].type == JointType::kRevolute;
    double value = fit.offsets[i] * (revolute ? 180 / M_PI : 1e3);
    if (value == 0.0) value = 0.0;                              // never -0
    const double shown = std::abs(value) < 5e-5 ? 0.0 : value;  // nor "-0.0000" in the text
    const char* name = installed.joints[i].name.c_str();
    const char* unit = revolute ? "deg" : "mm";
    const char* note = i == 0       ? "  (not observable: turns the arm and the scene together)"
                       : i + 1 == n ? "  (part of the sensor mount)"
                                    : "";
    std::snprintf(line, sizeof line, "  %s %+.4f %s%s\n", name, shown, unit, note);
    out.text += line;
    std::snprintf(line, sizeof line, "    - {name: %s, %s: %.9g}\n", name,
                  revolute ? "offset_deg" : "offset_mm", value);
    out.yaml += line;
    if (i == 0 || i + 1 == n) continue;  // not observable, or part of the mount
    std::snprintf(line, sizeof line, "%s %s %+.4f %s", i == 1 ? "" : ",", name, shown, unit);
    out.summary += line;
  }
  std::snprintf(line, sizeof line,
                "  sensor mount change %.3f mm, %.4f deg; unexplained by offsets and mount %.4f mm "
                "RMS\n",
                fit.mount_shift_m * 1e3, fit.mount_turn_rad * 180 / M_PI, fit.rms_position_m * 1e3);
  out.text += line;
  std::snprintf(line, sizeof line,
                "  mount_shift_m: %.9g\n  mount_turn_rad: %.9g\n  unexplained_rms_position_m: "
                "%.9g\n  samples: %zu\n",
                fit.mount_shift_m, fit.mount_turn_rad, fit.rms_position_m, fit.samples);
  out.yaml += line;
  std::snprintf(line, sizeof line, "; sensor mount %.3f mm, %.4f deg", fit.mount_shift_m * 1e3,
                fit.mount_turn_rad * 180 / M_PI);
  out.summary += line;
  return out;
}

}  // namespace selfcal::daemon
