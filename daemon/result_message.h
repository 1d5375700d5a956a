// calibration_result_t: published once per session with its outcome and reason, the validation
// RMS before and after, iterations, runtime, the installed model's path and every calibrated
// parameter before, after and with its standard deviation.
#pragma once

#include <cstdint>
#include <string>

#include "daemon/engine.h"
#include "daemon/history.h"
#include "daemon/state.h"
#include "selfcal/calibration_result_t.hpp"

namespace selfcal::daemon {

struct SessionOutcome {
  State outcome = State::kFailed;  // one of the terminal states
  std::string reason;
  std::int64_t utime = 0;
  std::string model_path;                  // the installed model; empty unless accepted
  const SessionRecord* record = nullptr;   // validation RMS, iterations, runtime
  const RobotModel* before = nullptr;      // the model the session started from, if read
  const CalibratedModel* after = nullptr;  // the engine's result, if it returned one
};

selfcal::calibration_result_t MakeResultMessage(const std::string& session_id,
                                                const SessionOutcome& outcome);

// The session's status word in session.yaml and the history: "accepted", "rejected", ...
const char* OutcomeWord(State outcome);

}  // namespace selfcal::daemon
