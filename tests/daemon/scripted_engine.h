// A calibration engine whose outcome the test chooses (it moves only what the job's mask frees,
// as the real engine), so that the daemon's own behaviour (gate,
// installation, abort and crash handling) is tested without minutes of real computation. The
// real engine (core/calib) is tested in tests/calib and end to end in daemon_e2e_test.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "daemon/clock.h"
#include "daemon/engine.h"

namespace selfcal::daemon::testing {

struct Script {
  double seconds = 0.5;       // computation time on the engine's clock, in steps that check `stop`
  double rms_before = 0.010;  // m, validation RMS of the current model
  double rms_after = 0.004;   // m, of the shifted one (rms_before when shift is 0)
  double shift = 0.002;       // added to the tool's z (m) of the current model
  bool fail = false;          // Calibrate returns an error
  bool usable = true;
  double predicted_error = 0.0005;  // m, the covariance's predicted sensor position error (RMS)
  // A motor swap the engine finds: joint `offset_joint` (1-based; 0 = none) turned at its zero by
  // `offset_deg` (WithJointOffsets), as far as the job's mask lets it move.
  int offset_joint = 0;
  double offset_deg = 0;
  double nudge = 0;  // added to every parameter the job's mask frees (rad or m)
};

// "seconds=2,rms_before=0.01,rms_after=0.004,shift=0.002,fail=0,usable=1,predicted_error=0.0005,
// offset_joint=4,offset_deg=0.5,nudge=1e-4";
// empty = defaults.
Expected<Script> ParseScript(const std::string& text);

class ScriptedEngine final : public CalibrationEngine {
 public:
  // `clock`: the daemon's, so that a test in simulated time computes in simulated time too.
  explicit ScriptedEngine(Script script,
                          std::shared_ptr<const Clock> clock = std::make_shared<SystemClock>())
      : script_(script), clock_(std::move(clock)) {}
  Expected<CalibratedModel> Calibrate(const CalibrationJob& job, const ProgressCallback& progress,
                                      const std::atomic<bool>& stop) override;

 private:
  // Waits `seconds` on the clock; false when `stop` came first.
  bool Wait(double seconds, const std::atomic<bool>& stop) const;

  Script script_;
  std::shared_ptr<const Clock> clock_;
};

}  // namespace selfcal::daemon::testing
