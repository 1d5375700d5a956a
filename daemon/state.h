// The daemon's states, as calibration_status_t carries them on the wire:
// IDLE -> CHECKING -> MOVING <-> RECORDING -> CALIBRATING -> VALIDATING -> ACCEPTED | REJECTED,
// and ABORTED (by request) and FAILED (with the reason) from any active state, then IDLE.
#pragma once

#include <cstdint>
#include <optional>

#include "selfcal/calibration_status_t.hpp"

namespace selfcal::daemon {

enum class State : std::int8_t {
  kIdle = selfcal::calibration_status_t::IDLE,
  kChecking = selfcal::calibration_status_t::CHECKING,
  kMoving = selfcal::calibration_status_t::MOVING,
  kRecording = selfcal::calibration_status_t::RECORDING,
  kCalibrating = selfcal::calibration_status_t::CALIBRATING,
  kValidating = selfcal::calibration_status_t::VALIDATING,
  kAccepted = selfcal::calibration_status_t::ACCEPTED,
  kRejected = selfcal::calibration_status_t::REJECTED,
  kAborted = selfcal::calibration_status_t::ABORTED,
  kFailed = selfcal::calibration_status_t::FAILED,
};

const char* StateName(State state);
// ACCEPTED, REJECTED, ABORTED and FAILED: how a session ends.
bool IsTerminal(State state);
// MOVING and RECORDING: the arm is executing the session's trajectory.
bool IsInMotion(State state);

inline std::int8_t ToWire(State state) { return static_cast<std::int8_t>(state); }
// Empty for a value no daemon sends (a newer or broken sender).
std::optional<State> StateFromWire(std::int8_t wire);
// The name of a received state, "UNKNOWN" for a value that is none.
const char* WireStateName(std::int8_t wire);

}  // namespace selfcal::daemon
