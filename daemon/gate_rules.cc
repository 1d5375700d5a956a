#include "daemon/gate_rules.h"

#include <algorithm>
#include <cstdio>
#include <string>

#include "core/model/evaluation.h"
#include "core/model/kinematics.h"
#include "daemon/gate.h"

namespace selfcal::daemon {
namespace {

std::string Format(const char* format, double a, double b = 0, double c = 0, double d = 0) {
  char text[200];
  std::snprintf(text, sizeof text, format, a, b, c, d);
  return text;
}

std::string Joined(const std::vector<std::string>& entries) {
  std::string text;
  for (const auto& entry : entries) text += (text.empty() ? "" : "; ") + entry;
  return text.empty() ? "none" : text;
}

std::string UncalibratedChanges(const RobotModel& before, const RobotModel& after) {
  const std::vector<double> k_before = ToParameterVector(before),
                            k_after = ToParameterVector(after);
  std::size_t changed = 0;
  for (std::size_t i = 0; i < k_before.size() && i < before.mask.size(); ++i) {
    changed += !before.mask[i] && k_after[i] != k_before[i] ? 1 : 0;
  }
  return std::to_string(changed) + " changed";
}

// A bound on a sensor position error [m] and its RMS and worst; a negative RMS is not known.
report::GateRule PositionBoundRule(const char* rule, double bound, double rms, double worst) {
  return {rule, Format("<= %.4f mm", bound * 1e3),
          rms >= 0 ? Format("%.4f mm (worst %.4f mm)", rms * 1e3, worst * 1e3) : "not known"};
}

void AddValidationRules(const AcceptanceConfig& config, const ValidationEvidence& v,
                        std::vector<report::GateRule>& rules) {
  rules.push_back({"the new model matches about as many validation points",
                   Format(">= %.0f (%.0f less %.0f sigma sqrt(N))",
                          static_cast<double>(v.matches_before) - FewerMatchesAllowed(v),
                          static_cast<double>(v.matches_before), kToleranceSigmas),
                   std::to_string(v.matches_after)});
  const double tolerance = ValidationTolerance(v);
  rules.push_back({"validation RMS not worse than the current model's beyond the tolerance",
                   Format("<= %.4f mm (%.4f mm + %.4f mm)", (v.rms_before + tolerance) * 1e3,
                          v.rms_before * 1e3, tolerance * 1e3),
                   Format("%.4f mm", v.rms_after * 1e3)});
  if (config.min_improvement <= 0) return;
  const double floor = config.noise_floor;
  const double part_before = ModelErrorPart(v.rms_before, floor);
  rules.push_back({"validation RMS above the noise floor drops by min_improvement",
                   Format("<= %.4f mm (%.1f %% less than %.4f mm; noise floor %.4f mm)",
                          (1 - config.min_improvement) * part_before * 1e3,
                          config.min_improvement * 100, part_before * 1e3, floor * 1e3),
                   Format("%.4f mm", ModelErrorPart(v.rms_after, floor) * 1e3)});
}

void AddLinkRules(const AcceptanceConfig& config, const RobotModel& before, const RobotModel& after,
                  std::vector<report::GateRule>& rules) {
  if (before.JointCount() != after.JointCount() || before.JointCount() == 0) return;
  const std::vector<LinkChange> changes = LinkChanges(before, after);
  const auto turn = std::max_element(changes.begin(), changes.end(),
                                     [](auto& a, auto& b) { return a.turn_rad < b.turn_rad; });
  const auto shift = std::max_element(changes.begin(), changes.end(),
                                      [](auto& a, auto& b) { return a.shift_m < b.shift_m; });
  rules.push_back({"no link turns more than max_angle_change_rad",
                   Format("%.6f rad", config.max_angle_change),
                   Format("%.6f rad", turn->turn_rad) + " (" + turn->link + ")"});
  rules.push_back({"no link moves more than max_translation_change_m",
                   Format("%.6f m", config.max_translation_change),
                   Format("%.6f m", shift->shift_m) + " (" + shift->link + ")"});
}

}  // namespace

std::vector<report::GateRule> DescribeGateRules(const AcceptanceConfig& config,
                                                const RobotModel& current,
                                                const CalibratedModel& result) {
  const bool measured = result.validation_rms_before >= 0 && result.validation_rms_after >= 0;
  std::vector<report::GateRule> rules;
  rules.push_back(
      {"validation scans were measured", "at least one", measured ? "yes" : "no validation scans"});
  rules.push_back({"the engine calls the result usable and it converged", "usable, converged",
                   (result.usable ? "yes: " : "no: ") + result.message});
  rules.push_back({"no calibrated parameter is unobservable", "none", Joined(result.unobservable)});
  rules.push_back(PositionBoundRule("predicted sensor position error (RMS over the workspace)",
                                    config.max_predicted_error, result.predicted_error,
                                    result.predicted_worst_error));
  if (config.max_held_out_offset > 0) {
    rules.push_back(PositionBoundRule(
        "held-out scans registered onto the fit scans: sensor origin moved (RMS)",
        config.max_held_out_offset, result.held_out_offset, result.held_out_worst_offset));
  }
  rules.push_back({"uncalibrated parameters unchanged", "0 changed",
                   UncalibratedChanges(current, result.model)});
  if (measured) {
    AddValidationRules(config,
                       {result.validation_rms_before, result.validation_rms_after,
                        result.validation_matches_before, result.validation_matches_after},
                       rules);
  }
  AddLinkRules(config, current, result.model, rules);
  return rules;
}

}  // namespace selfcal::daemon
