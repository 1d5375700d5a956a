// The acceptance gate's rules as rows for the session report: each rule in JudgeCalibration's
// order with its bound and this result's number, computed with the gate's own formulas
// (daemon/gate.h), so the report shows what the gate looked at. The decision stays the gate's.
#pragma once

#include <vector>

#include "core/model/robot_model.h"
#include "daemon/config.h"
#include "daemon/engine.h"
#include "protocols/report/report.h"

namespace selfcal::daemon {

std::vector<report::GateRule> DescribeGateRules(const AcceptanceConfig& config,
                                                const RobotModel& current,
                                                const CalibratedModel& result);

}  // namespace selfcal::daemon
