// The acceptance gate: a new model replaces the current one only if it explains the held-back
// validation scans better by a configured margin and no parameter moved implausibly far.
//
// The margin is taken on the part of the validation RMS that the model can explain. Residuals
// are sensor noise plus model error; with the two independent, RMS^2 = floor^2 + model^2, where
// `floor` is what a correct model reaches (acceptance.noise_floor_m). On noise-dominated sensors
// a good calibration moves the plain RMS only a few percent (Hokuyo: 8.3 -> 7.8 mm, docs/daemon.md)
// while removing most of the model part; a fixed percentage of the plain RMS cannot tell that from
// chance. With noise_floor_m 0 the rule is the plain relative one.
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

// The engine works on parameters normalized by its scale s (k / s, then back), so an uncalibrated
// parameter can come back one ulp off (0.35999999999999999 -> 0.36000000000000004 for base.z in
// a demo session, which the gate's exact check then rejected). Sets every uncalibrated parameter
// of `calibrated` that differs from `current` by no more than round-off (1e-12 relative) back to
// the current value, exactly; larger changes are left for the gate to refuse. Returns how many.
int RestoreRoundOff(const RobotModel& current, RobotModel& calibrated);

GateDecision ApplyAcceptanceGate(const AcceptanceConfig& config, const RobotModel& before,
                                 const RobotModel& after, const ValidationEvidence& validation);

// Everything the daemon decides on an engine result before installing it: the validation scans
// were measured, the engine's result is usable and converged (CalibratedModel::usable), and, after
// RestoreRoundOff() on `result.model`, ApplyAcceptanceGate() accepts it against `current`.
// `selfcal calibrate` prints this decision as `usable`, so that the word means what selfcald
// would install.
GateDecision JudgeCalibration(const AcceptanceConfig& config, const RobotModel& current,
                              CalibratedModel& result);

}  // namespace selfcal::daemon
