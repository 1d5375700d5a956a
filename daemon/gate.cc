#include "daemon/gate.h"

#include <cmath>
#include <sstream>

namespace selfcal::daemon {

GateDecision ApplyAcceptanceGate(const AcceptanceConfig& config, const RobotModel& before,
                                 const RobotModel& after, double rms_before, double rms_after) {
  std::ostringstream why;
  if (before.ParameterCount() != after.ParameterCount() || before.JointCount() != after.JointCount()) {
    return {false, "the new model has a different structure than the current one"};
  }
  if (!std::isfinite(rms_before) || !std::isfinite(rms_after) || rms_before <= 0 || rms_after < 0) {
    why << "validation residuals are not usable (before " << rms_before << " m, after " << rms_after << " m)";
    return {false, why.str()};
  }
  const double limit = (1.0 - config.min_improvement) * rms_before;
  if (rms_after > limit) {
    why << "validation RMS " << rms_after * 1e3 << " mm does not improve on " << rms_before * 1e3
        << " mm by the required " << config.min_improvement * 100 << " % (limit " << limit * 1e3 << " mm)";
    return {false, why.str()};
  }
  const auto k_before = ToParameterVector(before);
  const auto k_after = ToParameterVector(after);
  for (std::size_t i = 0; i < k_before.size(); ++i) {
    const double change = k_after[i] - k_before[i];
    if (!std::isfinite(k_after[i])) return {false, "parameter " + ParameterName(before, i) + " is not finite"};
    if (!before.mask[i]) {
      if (change != 0) return {false, "parameter " + ParameterName(before, i) + " is not calibrated but changed"};
      continue;
    }
    const bool translation = IsTranslationParameter(before, i);
    const double bound = translation ? config.max_translation_change : config.max_angle_change;
    if (std::abs(change) > bound) {
      why << "parameter " << ParameterName(before, i) << " moved by " << change
          << (translation ? " m" : " rad") << ", beyond the plausible bound of " << bound;
      return {false, why.str()};
    }
  }
  why << "validation RMS " << rms_before * 1e3 << " mm -> " << rms_after * 1e3 << " mm";
  return {true, why.str()};
}

}  // namespace selfcal::daemon
