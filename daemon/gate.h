// The acceptance gate: a new model replaces the current one only if the engine converged, the
// held-back validation scans exist and are not explained worse than by the current model beyond
// the noise of that comparison, the covariance's predicted sensor error is within the site's
// bound, no calibrated parameter is unobservable, and no link moved implausibly far. Every
// refusal names the rule and its numbers.
//
// Optionally (acceptance.min_improvement > 0) the new model must also improve the part of the
// validation RMS above a noise floor. Residuals are sensor noise plus model error; with the two
// independent, RMS^2 = floor^2 + model^2, where `floor` is what a correct model reaches
// (acceptance.noise_floor_m). A current model already at the floor has nothing to improve: then
// only "not worse" applies, so that recalibrating a correct model is accepted.
#pragma once

#include <cstddef>
#include <string>

#include "core/model/robot_model.h"
#include "daemon/config.h"
#include "daemon/engine.h"

namespace selfcal::daemon {

struct GateDecision {
  bool accepted = false;
  std::string reason;
};

// What the engine measured on the held-back scans, current model (before) and new one (after).
struct ValidationEvidence {
  double rms_before = -1;  // m, point-to-plane RMS of the validation matches
  double rms_after = -1;
  std::size_t matches_before = 0;  // validation matches; 0 = not known
  std::size_t matches_after = 0;
};

// The model-error part of a validation RMS above the noise floor: sqrt(max(rms^2 - floor^2, 0)).
double ModelErrorPart(double rms, double noise_floor);

// How many standard deviations of chance the validation comparisons allow.
inline constexpr double kToleranceSigmas = 3;

// How many fewer validation matches the new model may bring within d_max than the current one:
// 3 sqrt(N) of the current model's N, the chance of a model that explains the scans as well.
double FewerMatchesAllowed(const ValidationEvidence& validation);

// How much higher the new model's validation RMS may be than the current one's: three standard
// deviations of the difference of two RMS estimates over N matches of residuals with the spread
// the current model's RMS shows (the sensor's noise, for a correct model), 3 rms / sqrt(N) with
// N the smaller match count. 0 when the counts are not known.
double ValidationTolerance(const ValidationEvidence& validation);

// The engine works on parameters normalized by its scale s (k / s, then back), so an uncalibrated
// parameter can come back one ulp off (0.35999999999999999 -> 0.36000000000000004 for base.z in
// a demo session, which the gate's exact check then rejected). Sets every uncalibrated parameter
// of `calibrated` that differs from `current` by no more than round-off (1e-12 relative) back to
// the current value, exactly; larger changes are left for the gate to refuse. Returns how many.
int RestoreRoundOff(const RobotModel& current, RobotModel& calibrated);

GateDecision ApplyAcceptanceGate(const AcceptanceConfig& config, const RobotModel& before,
                                 const RobotModel& after, const ValidationEvidence& validation);

// Whether the recording's validation scans are required (selfcald: always). `selfcal calibrate
// --no-validation` judges a recording without them on the other rules, and says so.
enum class ValidationRule { kRequired, kSkipped };

// Everything the daemon decides on an engine result before installing it, in this order: the
// validation scans were measured, the engine's result is usable and converged
// (CalibratedModel::usable), no calibrated parameter is unobservable, the predicted sensor error
// is known and within acceptance.max_predicted_error_m, and, after RestoreRoundOff() on
// `result.model`, ApplyAcceptanceGate() accepts it against `current`. `selfcal calibrate` prints
// this decision as `usable`, so that the word means what selfcald would install.
GateDecision JudgeCalibration(const AcceptanceConfig& config, const RobotModel& current,
                              CalibratedModel& result,
                              ValidationRule validation = ValidationRule::kRequired);

}  // namespace selfcal::daemon
