// A calibration engine whose outcome the test chooses, so that the daemon's own behaviour (gate,
// installation, abort and crash handling) is tested without minutes of real computation. The
// real engine (core/calib) is tested in tests/calib and end to end in daemon_e2e_test.
#pragma once

#include <string>
#include <vector>

#include "daemon/engine.h"

namespace selfcal::daemon::testing {

struct Script {
  double seconds = 0.5;       // computation time, in steps that check `stop`
  double rms_before = 0.010;  // m
  double rms_after = 0.004;   // m
  double shift = 0.002;       // added to the tool's z (m) of the current model
  bool fail = false;          // Calibrate returns an error
  bool usable = true;
};

// "seconds=2,rms_before=0.01,rms_after=0.004,shift=0.002,fail=0,usable=1"; empty = defaults.
Expected<Script> ParseScript(const std::string& text);

class ScriptedEngine final : public CalibrationEngine {
 public:
  explicit ScriptedEngine(Script script) : script_(script) {}
  Expected<CalibratedModel> Calibrate(const CalibrationJob& job, const ProgressCallback& progress,
                                      const std::atomic<bool>& stop) override;
  Expected<double> ValidationRms(const CalibrationJob& job, const RobotModel& model,
                                 const std::atomic<bool>& stop) override;

 private:
  Script script_;
};

}  // namespace selfcal::daemon::testing
