#include "daemon/gate.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "core/model/evaluation.h"
#include "core/model/kinematics.h"

namespace selfcal::daemon {

double ModelErrorPart(double rms, double noise_floor) {
  return std::sqrt(std::max(rms * rms - noise_floor * noise_floor, 0.0));
}

double FewerMatchesAllowed(const ValidationEvidence& validation) {
  return kToleranceSigmas * std::sqrt(static_cast<double>(validation.matches_before));
}

double ValidationTolerance(const ValidationEvidence& validation) {
  const std::size_t matches = std::min(validation.matches_before, validation.matches_after);
  if (matches == 0 || !(validation.rms_before > 0)) return 0;
  return kToleranceSigmas * validation.rms_before / std::sqrt(static_cast<double>(matches));
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

std::string Millimetres(double metres) {
  std::ostringstream text;
  text << metres * 1e3 << " mm";
  return text.str();
}

// The current model's part above the floor must shrink by the margin, unless it is already at
// the floor within the tolerance; empty when it does, else why not.
std::string CheckImprovement(const AcceptanceConfig& config, const ValidationEvidence& v,
                             double tolerance) {
  const double floor = config.noise_floor;
  if (config.min_improvement <= 0 || v.rms_before <= floor + tolerance) return {};
  const double part_before = ModelErrorPart(v.rms_before, floor);
  const double part_after = ModelErrorPart(v.rms_after, floor);
  const double limit = (1.0 - config.min_improvement) * part_before;
  if (part_after <= limit) return {};
  std::ostringstream why;
  why << "validation RMS " << v.rms_before * 1e3 << " mm -> " << v.rms_after * 1e3
      << " mm: the part above the " << floor * 1e3 << " mm noise floor goes " << part_before * 1e3
      << " -> " << part_after * 1e3 << " mm, which does not improve by the required "
      << config.min_improvement * 100 << " % (limit " << limit * 1e3 << " mm)";
  return why.str();
}

// The validation residual must not be worse beyond the tolerance (and improve by the optional
// margin); empty when so, else why not.
std::string CheckValidation(const AcceptanceConfig& config, const ValidationEvidence& v) {
  std::ostringstream why;
  if (!std::isfinite(v.rms_before) || !std::isfinite(v.rms_after) || v.rms_before <= 0 ||
      v.rms_after < 0) {
    why << "validation residuals are not usable (before " << v.rms_before << " m, after "
        << v.rms_after << " m)";
    return why.str();
  }
  // Matches are the pairs within d_max: a model can lower the RMS of the rest by losing its worst
  // matches. One that explains the scans as well brings as many within d_max, up to chance.
  const double fewer_allowed = FewerMatchesAllowed(v);
  if (v.matches_before > 0 && static_cast<double>(v.matches_after) + fewer_allowed <
                                  static_cast<double>(v.matches_before)) {
    why << "the new model matches fewer validation points (" << v.matches_after << " < "
        << v.matches_before << ", beyond the tolerance of " << fewer_allowed << ")";
    return why.str();
  }
  const double tolerance = ValidationTolerance(v);
  if (v.rms_after > v.rms_before + tolerance) {
    why << "validation RMS " << v.rms_before * 1e3 << " mm -> " << v.rms_after * 1e3
        << " mm: worse than the current model beyond the tolerance of " << tolerance * 1e3
        << " mm (" << kToleranceSigmas << " sigma of the difference over "
        << std::min(v.matches_before, v.matches_after) << " matches)";
    return why.str();
  }
  return CheckImprovement(config, v, tolerance);
}

// The structure is kept, every parameter finite, uncalibrated ones unchanged.
std::string CheckParameters(const RobotModel& before, const RobotModel& after) {
  if (before.ParameterCount() != after.ParameterCount() ||
      before.JointCount() != after.JointCount()) {
    return "the new model has a different structure than the current one";
  }
  const auto k_before = ToParameterVector(before);
  const auto k_after = ToParameterVector(after);
  for (std::size_t i = 0; i < k_before.size(); ++i) {
    if (!std::isfinite(k_after[i]))
      return "parameter " + ParameterName(before, i) + " is not finite";
    if (!before.mask[i] && k_after[i] != k_before[i]) {
      return "parameter " + ParameterName(before, i) + " is not calibrated but changed";
    }
  }
  return {};
}

// Plausible jumps are bounded per link, on the transform, not per parameter: near beta = -90 deg
// (a sensor mounted at right angles, as in the demo) the tool's alpha and gamma turn about the
// same axis, so only alpha - gamma is observable and the engine may move both by the same large
// amount without changing the model at all (4.1 deg each in a demo session, rejected before).
std::string CheckLinkChanges(const AcceptanceConfig& config, const RobotModel& before,
                             const RobotModel& after) {
  std::ostringstream why;
  for (const LinkChange& change : LinkChanges(before, after)) {
    if (change.turn_rad > config.max_angle_change) {
      why << change.link << " turns by " << change.turn_rad
          << " rad, beyond the plausible bound of " << config.max_angle_change;
      return why.str();
    }
    if (change.shift_m > config.max_translation_change) {
      why << change.link << " moves by " << change.shift_m << " m, beyond the plausible bound of "
          << config.max_translation_change;
      return why.str();
    }
  }
  return {};
}

}  // namespace

GateDecision ApplyAcceptanceGate(const AcceptanceConfig& config, const RobotModel& before,
                                 const RobotModel& after, const ValidationEvidence& validation) {
  if (auto refused = CheckParameters(before, after); !refused.empty()) return {false, refused};
  if (auto refused = CheckValidation(config, validation); !refused.empty()) return {false, refused};
  if (auto refused = CheckLinkChanges(config, before, after); !refused.empty())
    return {false, refused};
  std::ostringstream why;
  why << "validation RMS " << validation.rms_before * 1e3 << " mm -> " << validation.rms_after * 1e3
      << " mm";
  if (validation.matches_before > 0) {
    why << " (tolerance " << ValidationTolerance(validation) * 1e3 << " mm), "
        << validation.matches_before << " -> " << validation.matches_after << " matches";
  }
  if (config.min_improvement > 0 && config.noise_floor > 0) {
    why << ", above the " << config.noise_floor * 1e3
        << " mm noise floor: " << ModelErrorPart(validation.rms_before, config.noise_floor) * 1e3
        << " -> " << ModelErrorPart(validation.rms_after, config.noise_floor) * 1e3 << " mm";
  }
  return {true, why.str()};
}

namespace {

// The optional rule on the held-out scans' registration (acceptance.max_held_out_offset_m).
std::string CheckHeldOut(const AcceptanceConfig& config, const CalibratedModel& result) {
  if (config.max_held_out_offset <= 0) return {};
  if (!(result.held_out_offset >= 0)) {
    return "no held-out scan could be registered onto the fit scans, so the result cannot be "
           "held to the bound of " +
           Millimetres(config.max_held_out_offset) + " (acceptance.max_held_out_offset_m)";
  }
  if (result.held_out_offset <= config.max_held_out_offset) return {};
  std::ostringstream why;
  why << "the held-out scans, registered onto the fit scans, move their sensor origins "
      << result.held_out_offset * 1e3 << " mm RMS (worst " << result.held_out_worst_offset * 1e3
      << " mm), beyond the bound of " << config.max_held_out_offset * 1e3
      << " mm (acceptance.max_held_out_offset_m)";
  return why.str();
}

// " (H mm of it from what the calibration holds ...)" when it holds something, else "".
std::string HeldPart(const CalibratedModel& result) {
  if (!(result.predicted_held_error >= 0)) return "";
  std::ostringstream part;
  part << " (" << result.predicted_held_error * 1e3
       << " mm of it from what the calibration holds at assumed values)";
  return part.str();
}

// The rules on what the engine knows about its own result: observability, predicted error and,
// optionally, the held-out scans' registration.
std::string CheckCertainty(const AcceptanceConfig& config, const CalibratedModel& result) {
  if (!result.unobservable.empty()) {
    std::string names;
    for (const auto& entry : result.unobservable) names += (names.empty() ? "" : "; ") + entry;
    return "unobservable: " + names;
  }
  if (!(result.predicted_error >= 0)) {
    return "the engine gives no predicted error (no covariance), so it cannot be held to the "
           "bound of " +
           Millimetres(config.max_predicted_error);
  }
  if (result.predicted_error > config.max_predicted_error) {
    std::ostringstream why;
    why << "predicted sensor position error " << result.predicted_error * 1e3
        << " mm RMS over the workspace (worst " << result.predicted_worst_error * 1e3 << " mm)"
        << HeldPart(result) << " exceeds the bound of " << config.max_predicted_error * 1e3
        << " mm (acceptance.max_predicted_error_m)";
    return why.str();
  }
  return CheckHeldOut(config, result);
}

}  // namespace

GateDecision JudgeCalibration(const AcceptanceConfig& config, const RobotModel& current,
                              CalibratedModel& result, ValidationRule validation) {
  const bool measured = result.validation_rms_before >= 0 && result.validation_rms_after >= 0;
  // A calibration that never ran (bad input or options) measured no validation either: its
  // own reason is the one to name.
  if (!result.usable && result.iterations == 0)
    return {false, "the engine's result is not usable: " + result.message};
  if (validation == ValidationRule::kRequired && !measured) {
    return {false, "validation failed: the recording has no validation scans"};
  }
  if (!result.usable) return {false, "the engine's result is not usable: " + result.message};
  if (auto refused = CheckCertainty(config, result); !refused.empty()) return {false, refused};
  RestoreRoundOff(current, result.model);
  GateDecision decision;
  if (measured) {
    decision =
        ApplyAcceptanceGate(config, current, result.model,
                            {result.validation_rms_before, result.validation_rms_after,
                             result.validation_matches_before, result.validation_matches_after});
  } else {
    std::string refused = CheckParameters(current, result.model);
    if (refused.empty()) refused = CheckLinkChanges(config, current, result.model);
    decision = {refused.empty(),
                refused.empty() ? "no validation scans (--no-validation)" : refused};
  }
  if (!decision.accepted) return decision;
  std::ostringstream why;
  why << decision.reason << "; predicted sensor position error " << result.predicted_error * 1e3
      << " mm RMS, worst " << result.predicted_worst_error * 1e3 << " mm" << HeldPart(result)
      << " (bound " << config.max_predicted_error * 1e3 << " mm)";
  // The held-out scans' registration sees what the prediction cannot (held_out_registration.h):
  // the technician reads the two side by side.
  if (result.held_out_offset >= 0)
    why << "; held-out scans moved " << result.held_out_offset * 1e3 << " mm RMS";
  if (config.max_held_out_offset > 0)
    why << " (bound " << config.max_held_out_offset * 1e3 << " mm)";
  return {true, why.str()};
}

}  // namespace selfcal::daemon
