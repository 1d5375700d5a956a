// The session's report (protocols/report), written into its folder once the gate has decided,
// whatever it decided: what the daemon knows of the session, in the report's terms. Copies, so
// that the report can be written beside the daemon's loop while the next session starts.
#pragma once

#include <string>

#include "core/model/robot_model.h"
#include "core/util/expected.h"
#include "daemon/config.h"
#include "daemon/engine.h"
#include "daemon/gate.h"

namespace selfcal::daemon {

struct SessionReport {
  std::string path;  // sessions/<id>/report.html
  std::string session_id;
  std::string recording_path;
  std::string current_id;  // the model the session started from
  RobotModel current;
  CalibratedModel result;
  GateDecision decision;
};

// Reads the session's recording again (the engine's datasets are gone by now): seconds
// (docs/report.md), so the daemon calls it on a thread of its own.
Status WriteSessionReport(const DaemonConfig& config, const SessionReport& session);

}  // namespace selfcal::daemon
