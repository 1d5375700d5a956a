#include "daemon/gate.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "core/model/kinematics.h"

namespace selfcal::daemon {

double ModelErrorPart(double rms, double noise_floor) {
  return std::sqrt(std::max(rms * rms - noise_floor * noise_floor, 0.0));
}

int RestoreRoundOff(const RobotModel& current, RobotModel& calibrated) {
  if (current.ParameterCount() != calibrated.ParameterCount() ||
      current.mask.size() != current.ParameterCount()) {
    return 0;
  }
  const std::vector<double> k_current = ToParameterVector(current);
  std::vector<double> k = ToParameterVector(calibrated);
  int restored = 0;
  for (std::size_t i = 0; i < k.size(); ++i) {
    const double change = std::abs(k[i] - k_current[i]);
    if (!current.mask[i] && change > 0 && change <= 1e-12 * std::max(1.0, std::abs(k_current[i]))) {
      k[i] = k_current[i];
      ++restored;
    }
  }
  if (restored > 0) FromParameterVector(k, calibrated);
  return restored;
}

namespace {

// The validation residual must improve; empty when it does, else why not.
std::string CheckValidation(const AcceptanceConfig& config, const ValidationEvidence& v) {
  std::ostringstream why;
  if (!std::isfinite(v.rms_before) || !std::isfinite(v.rms_after) || v.rms_before <= 0 ||
      v.rms_after < 0) {
    why << "validation residuals are not usable (before " << v.rms_before << " m, after "
        << v.rms_after << " m)";
    return why.str();
  }
  // Matches are the pairs within d_max: a model can lower the RMS of the rest by losing its worst
  // matches. One that explains the scans better brings more of them within d_max, not fewer.
  if (v.matches_before > 0 && v.matches_after < v.matches_before) {
    why << "the new model matches fewer validation points (" << v.matches_after << " < "
        << v.matches_before << ")";
    return why.str();
  }
  const double floor = config.noise_floor;
  const double part_before = ModelErrorPart(v.rms_before, floor);
  const double part_after = ModelErrorPart(v.rms_after, floor);
  if (part_before <= 0) {
    why << "validation RMS " << v.rms_before * 1e3
        << " mm of the current model is already at the noise floor of " << floor * 1e3
        << " mm: nothing to improve";
    return why.str();
  }
  const double limit = (1.0 - config.min_improvement) * part_before;
  if (part_after > limit) {
    why << "validation RMS " << v.rms_before * 1e3 << " mm -> " << v.rms_after * 1e3
        << " mm: the part above the " << floor * 1e3 << " mm noise floor goes " << part_before * 1e3
        << " -> " << part_after * 1e3 << " mm, which does not improve by the required "
        << config.min_improvement * 100 << " % (limit " << limit * 1e3 << " mm)";
    return why.str();
  }
  return {};
}

// Each link of the MCPC model (base, segments, tool) as the rigid transform its parameters define.
struct Link {
  std::string name;
  Transform3<double> transform;
};

std::vector<Link> Links(const RobotModel& model) {
  const std::vector<double> k = ToParameterVector(model);
  const auto name = [&](std::size_t offset) {
    const std::string parameter = ParameterName(model, offset);
    return parameter.substr(0, parameter.rfind('.'));
  };
  std::vector<Link> links{{name(kBaseOffset), FullTransform(k.data() + kBaseOffset)}};
  for (std::size_t i = 0; i + 1 < model.JointCount(); ++i) {
    links.push_back({name(SegmentOffset(i)), SegmentTransform(k.data() + SegmentOffset(i))});
  }
  links.push_back({name(ToolOffset(model.JointCount())),
                   FullTransform(k.data() + ToolOffset(model.JointCount()))});
  return links;
}

// Plausible jumps are bounded per link, on the transform, not per parameter: near beta = -90 deg
// (a sensor mounted at right angles, as in the demo) the tool's alpha and gamma turn about the
// same axis, so only alpha - gamma is observable and the engine may move both by the same large
// amount without changing the model at all (4.1 deg each in a demo session, rejected before).
std::string CheckLinkChanges(const AcceptanceConfig& config, const RobotModel& before,
                             const RobotModel& after) {
  const std::vector<Link> from = Links(before), to = Links(after);
  std::ostringstream why;
  for (std::size_t i = 0; i < from.size(); ++i) {
    const double angle =
        Eigen::AngleAxisd(from[i].transform.linear().transpose() * to[i].transform.linear())
            .angle();
    const double shift = (to[i].transform.translation() - from[i].transform.translation()).norm();
    if (angle > config.max_angle_change) {
      why << from[i].name << " turns by " << angle << " rad, beyond the plausible bound of "
          << config.max_angle_change;
      return why.str();
    }
    if (shift > config.max_translation_change) {
      why << from[i].name << " moves by " << shift << " m, beyond the plausible bound of "
          << config.max_translation_change;
      return why.str();
    }
  }
  return {};
}

}  // namespace

GateDecision ApplyAcceptanceGate(const AcceptanceConfig& config, const RobotModel& before,
                                 const RobotModel& after, const ValidationEvidence& validation) {
  std::ostringstream why;
  if (before.ParameterCount() != after.ParameterCount() ||
      before.JointCount() != after.JointCount()) {
    return {false, "the new model has a different structure than the current one"};
  }
  if (auto refused = CheckValidation(config, validation); !refused.empty()) return {false, refused};
  const auto k_before = ToParameterVector(before);
  const auto k_after = ToParameterVector(after);
  for (std::size_t i = 0; i < k_before.size(); ++i) {
    if (!std::isfinite(k_after[i]))
      return {false, "parameter " + ParameterName(before, i) + " is not finite"};
    if (!before.mask[i] && k_after[i] != k_before[i]) {
      return {false, "parameter " + ParameterName(before, i) + " is not calibrated but changed"};
    }
  }
  if (auto refused = CheckLinkChanges(config, before, after); !refused.empty())
    return {false, refused};
  why << "validation RMS " << validation.rms_before * 1e3 << " mm -> " << validation.rms_after * 1e3
      << " mm";
  if (config.noise_floor > 0) {
    why << " (above the " << config.noise_floor * 1e3
        << " mm noise floor: " << ModelErrorPart(validation.rms_before, config.noise_floor) * 1e3
        << " -> " << ModelErrorPart(validation.rms_after, config.noise_floor) * 1e3 << " mm)";
  }
  if (validation.matches_before > 0) {
    why << ", " << validation.matches_before << " -> " << validation.matches_after << " matches";
  }
  return {true, why.str()};
}

GateDecision JudgeCalibration(const AcceptanceConfig& config, const RobotModel& current,
                              CalibratedModel& result) {
  if (result.validation_rms_before < 0 || result.validation_rms_after < 0) {
    return {false, "validation failed: the recording has no validation scans"};
  }
  if (!result.usable) return {false, "the engine's result is not usable: " + result.message};
  RestoreRoundOff(current, result.model);
  const ValidationEvidence validation{result.validation_rms_before, result.validation_rms_after,
                                      result.validation_matches_before,
                                      result.validation_matches_after};
  return ApplyAcceptanceGate(config, current, result.model, validation);
}

}  // namespace selfcal::daemon
