// The acceptance gate's rules with this session's numbers, for the report. The decision itself
// is the gate's (daemon/gate.h); this only lists what it looks at.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/model/evaluation.h"
#include "protocols/report/report.h"

namespace selfcal::report {
namespace {

std::string Format(const char* format, double a, double b = 0, double c = 0, double d = 0) {
  char text[160];
  std::snprintf(text, sizeof text, format, a, b, c, d);
  return text;
}

double AboveFloor(double rms, double floor) {
  return std::sqrt(std::max(rms * rms - floor * floor, 0.0));
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

}  // namespace

std::vector<GateRule> DescribeGateRules(const AcceptanceBounds& bounds, const EngineVerdict& engine,
                                        const RobotModel& before, const RobotModel& after,
                                        const calib::ValidationReport& validation) {
  std::vector<GateRule> rules;
  rules.push_back({"validation scans were measured", "at least one",
                   validation.available ? "yes" : "no validation scans"});
  rules.push_back({"the engine calls the result usable and it converged", "usable, converged",
                   (engine.usable_and_converged ? "yes: " : "no: ") + engine.termination});
  rules.push_back({"the new model matches at least as many validation points",
                   std::to_string(validation.matches_before),
                   std::to_string(validation.matches_after)});
  const double floor = bounds.noise_floor_m;
  const double part_before = AboveFloor(validation.rms_before_m, floor);
  const double part_after = AboveFloor(validation.rms_after_m, floor);
  rules.push_back({"validation RMS above the noise floor drops by min_improvement",
                   Format("<= %.4f mm (%.1f %% less than %.4f mm; noise floor %.4f mm)",
                          (1 - bounds.min_improvement) * part_before * 1e3,
                          bounds.min_improvement * 100, part_before * 1e3, floor * 1e3),
                   Format("%.4f mm (RMS %.4f -> %.4f mm)", part_after * 1e3,
                          validation.rms_before_m * 1e3, validation.rms_after_m * 1e3)});
  rules.push_back(
      {"uncalibrated parameters unchanged", "0 changed", UncalibratedChanges(before, after)});
  if (before.JointCount() == after.JointCount() && before.JointCount() > 0) {
    const std::vector<LinkChange> changes = LinkChanges(before, after);
    const auto turn = std::max_element(changes.begin(), changes.end(),
                                       [](auto& a, auto& b) { return a.turn_rad < b.turn_rad; });
    const auto shift = std::max_element(changes.begin(), changes.end(),
                                        [](auto& a, auto& b) { return a.shift_m < b.shift_m; });
    rules.push_back({"no link turns more than max_angle_change_rad",
                     Format("%.6f rad", bounds.max_angle_change_rad),
                     Format("%.6f rad", turn->turn_rad) + " (" + turn->link + ")"});
    rules.push_back({"no link moves more than max_translation_change_m",
                     Format("%.6f m", bounds.max_translation_change_m),
                     Format("%.6f m", shift->shift_m) + " (" + shift->link + ")"});
  }
  return rules;
}

}  // namespace selfcal::report
