// The acceptance gate: a new model replaces the current one only if it explains the held-back
// validation scans better by a configured margin and no parameter moved implausibly far.
#pragma once

#include <string>

#include "core/model/robot_model.h"
#include "daemon/config.h"

namespace selfcal::daemon {

struct GateDecision {
  bool accepted = false;
  std::string reason;
};

GateDecision ApplyAcceptanceGate(const AcceptanceConfig& config, const RobotModel& before,
                                 const RobotModel& after, double rms_before, double rms_after);

}  // namespace selfcal::daemon
