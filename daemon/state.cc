#include "daemon/state.h"

namespace selfcal::daemon {

const char* StateName(State state) {
  switch (state) {
    case State::kIdle:
      return "IDLE";
    case State::kChecking:
      return "CHECKING";
    case State::kMoving:
      return "MOVING";
    case State::kRecording:
      return "RECORDING";
    case State::kCalibrating:
      return "CALIBRATING";
    case State::kValidating:
      return "VALIDATING";
    case State::kAccepted:
      return "ACCEPTED";
    case State::kRejected:
      return "REJECTED";
    case State::kAborted:
      return "ABORTED";
    case State::kFailed:
      return "FAILED";
  }
  return "UNKNOWN";
}

bool IsTerminal(State state) {
  return state == State::kAccepted || state == State::kRejected || state == State::kAborted ||
         state == State::kFailed;
}

bool IsInMotion(State state) { return state == State::kMoving || state == State::kRecording; }

std::optional<State> StateFromWire(std::int8_t wire) {
  if (wire < ToWire(State::kIdle) || wire > ToWire(State::kFailed)) return std::nullopt;
  return static_cast<State>(wire);
}

const char* WireStateName(std::int8_t wire) {
  const auto state = StateFromWire(wire);
  return state ? StateName(*state) : "UNKNOWN";
}

}  // namespace selfcal::daemon
