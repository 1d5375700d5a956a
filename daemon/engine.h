// The seam between the daemon and the calibration engine. The production implementation
// (engine_calib.cc) runs the code of `selfcal calibrate`; tests may plug their own engine to
// exercise the daemon's gate, crash and abort handling without minutes of computation.
#pragma once

#include <atomic>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/model/robot_model.h"
#include "core/util/expected.h"
#include "protocols/lcm/channels.h"

namespace selfcal::calib {
struct CalibrationResult;
}

namespace selfcal::daemon {

struct CalibrationJob {
  std::string session_id;
  std::string joint_state_channel = channels::kJointState;
  std::string scan_marker_channel = channels::kScanMarker;
  std::string sensor_channel = channels::kRangeScan;
  std::string recording_path;  // the session's committed LCM log
  std::string model_path;      // the current model file (the starting point)
  RobotModel current;
  std::string sensor_path;  // the sensor file (Table I parameters)
  int threads = 1;
};

struct CalibratedModel {
  RobotModel model;
  std::vector<double> stddev;  // per flat parameter; empty when the engine gives none
  int iterations = 0;
  double runtime = 0;  // s
  bool usable = false;
  std::string message;           // why it stopped, in the engine's words
  std::string calibration_yaml;  // extra provenance for the model file's `calibration:` key
  // Point-to-plane RMS [m] on the validation scans with the current and the new model; negative
  // = not measured (a recording without validation scans), which fails the session: the
  // acceptance gate has nothing to compare.
  double validation_rms_before = -1;
  double validation_rms_after = -1;
  std::size_t validation_matches_before = 0;  // 0 = not known
  std::size_t validation_matches_after = 0;
  // The sensor position error the engine's covariance predicts, RMS over the workspace (m, 1
  // sigma; core/calib/covariance.h); negative = not known, which the gate refuses.
  double predicted_error = -1;
  double predicted_worst_error = -1;  // m: the largest over the same configurations
  // m: the part of predicted_error from what the calibration holds at assumed values (the
  // sensor's intrinsics, a rigid arm's compliance; docs/engine.md deviation 21); negative =
  // nothing held.
  double predicted_held_error = -1;
  // How far the held-out scans' sensor origins move when each is registered onto the fit scans
  // (core/calib/held_out_registration.h), RMS and worst (m); negative = none registered.
  double held_out_offset = -1;
  double held_out_worst_offset = -1;
  // Calibrated parameters the scans cannot determine, with why; empty = all observed.
  std::vector<std::string> unobservable;
  // What changed against the current model, in words (core/model/model_change.h): "no
  // significant change", "joint A4 zero offset moved 0.41 deg (mastering lost?)", ...
  std::string change;
};

// The engine's result as the daemon judges it (daemon/gate.h, JudgeCalibration): usable only
// when the engine calls it usable and it converged; the validation RMS when measured; the
// predicted error and the unobservable parameters;
// `calibration_yaml` (FormatCalibrationYaml with the caller's provenance) for the model file.
CalibratedModel ToCalibratedModel(const calib::CalibrationResult& result, const RobotModel& current,
                                  std::string calibration_yaml);

// Which of the daemon's states the engine's work belongs to: CALIBRATING or VALIDATING.
enum class Phase { kCalibrating, kValidating };

// The phase, fraction in [0, 1] of it, and what is being done in plain words.
using ProgressCallback = std::function<void(Phase phase, double fraction, const std::string& what)>;

class CalibrationEngine {
 public:
  virtual ~CalibrationEngine() = default;
  // `stop` becomes true on an abort: return soon with an error.
  virtual Expected<CalibratedModel> Calibrate(const CalibrationJob& job,
                                              const ProgressCallback& progress,
                                              const std::atomic<bool>& stop) = 0;
};

// The engine of `selfcal calibrate` (core/calib). An EngineFactory (daemon/service_main.h), so
// that tests can put an engine of their own in its place.
Expected<std::unique_ptr<CalibrationEngine>> MakeDefaultEngine();

}  // namespace selfcal::daemon
