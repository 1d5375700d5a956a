// The production engine: exactly the code of `selfcal calibrate` (protocols/recording's
// LoadRecording and CalibrationOptionsFromSensor, core/calib's Calibrate).
#include <map>
#include <utility>

#include "core/calib/calibrate.h"
#include "daemon/engine.h"
#include "protocols/model_file/sensor_config.h"
#include "protocols/recording/recording.h"

namespace selfcal::daemon {
namespace {

class CalibEngine final : public CalibrationEngine {
 public:
  Expected<CalibratedModel> Calibrate(const CalibrationJob& job, const ProgressCallback& progress,
                                      const std::atomic<bool>& stop) override {
    auto sensor = ReadSensorConfig(job.sensor_path);
    if (!sensor) return sensor.error();
    recording::RecordingOptions recording_options;
    recording_options.channels.joint_state = job.joint_state_channel;
    recording_options.channels.scan_marker = job.scan_marker_channel;
    recording_options.SetSensorChannel(sensor->layout, job.sensor_channel);
    auto options = recording::CalibrationOptionsFromSensor(*sensor);
    options.threads = job.threads;
    // The sensor file's latency is the start (and, unless it says estimate: false for a
    // sweeping sensor, the engine estimates it): RecordingOptions::latency_s unset.
    recording_options.joint_timing = options.estimate_latency;  // what the latency needs
    // Before the recording is loaded: a bad option should not wait for that.
    if (std::string problem; !options.IsValid(&problem)) {
      return Error{job.sensor_path + ": calibration options: " + problem};
    }
    progress(Phase::kCalibrating, 0, "loading the recording");
    auto datasets =
        recording::LoadRecording(job.recording_path, job.current, *sensor, recording_options);
    if (!datasets) return datasets.error();
    auto on_progress = [&progress](const calib::CalibrationProgress& p) {
      const double fraction =
          p.max_iterations > 0 ? static_cast<double>(p.iteration) / p.max_iterations : 0.0;
      if (p.stage == calib::CalibrationStage::kValidation && p.iteration > 0) {
        progress(Phase::kValidating, 0.5, "validation");
      } else if (p.stage == calib::CalibrationStage::kValidation) {
        // Before the first iteration: the current model's residual on the validation scans.
        progress(Phase::kCalibrating, 0, "residual of the current model on the validation scans");
      } else {
        progress(Phase::kCalibrating, fraction,
                 "iteration " + std::to_string(p.iteration) + "/" +
                     std::to_string(p.max_iterations) + " " + calib::StageName(p.stage) + ", " +
                     std::to_string(p.valid_matches) + " matches");
      }
    };
    const calib::CalibrationResult result =
        calib::Calibrate(std::move(*datasets), job.current, options, on_progress, &stop);
    if (result.termination == calib::Termination::kCancelled) return Error{"cancelled"};
    if (result.termination == calib::Termination::kInvalidInput) return Error{result.message};
    // The sensor file and the recording as the engine read them; the model started from is the
    // installed one, named by the session's metadata.
    const auto provenance =
        recording::MakeProvenance(std::string("selfcald ") + SELFCAL_VERSION,
                                  {{"sensor", job.sensor_path}, {"recording", job.recording_path}});
    if (!provenance) return Error{provenance.error().message};
    return ToCalibratedModel(result, job.current,
                             recording::FormatCalibrationYaml(result, &*provenance));
  }
};

}  // namespace

CalibratedModel ToCalibratedModel(const calib::CalibrationResult& result, const RobotModel& current,
                                  std::string calibration_yaml) {
  CalibratedModel out;
  out.model = result.model;
  out.iterations = static_cast<int>(result.iterations.size());
  out.runtime = result.runtime_s;
  // Installing needs a converged result: one stopped by i_max may have drifted along directions
  // the scans do not observe while still fitting them better (photoneo-bunny with 7 scans:
  // validation RMS 9.4 -> 3.1 mm, sensor pose 30 -> 60 mm off; docs/accuracy.md).
  out.usable = result.usable && result.converged;
  out.message = std::string(calib::TerminationName(result.termination)) + ": " + result.message;
  out.calibration_yaml = std::move(calibration_yaml);
  if (result.change_known) out.change = result.change.Summary();
  std::map<std::string, double> stddev;
  for (const auto& parameter : result.parameters) stddev[parameter.name] = parameter.std_dev;
  out.stddev.assign(current.ParameterCount(), -1.0);
  for (std::size_t i = 0; i < out.stddev.size(); ++i) {
    const auto found = stddev.find(ParameterName(current, i));
    if (found != stddev.end()) out.stddev[i] = found->second;
  }
  // The gate's numbers as the result file keeps them (a report judges them again from it).
  if (result.validation.available) {
    out.validation_rms_before = recording::AsWritten(result.validation.rms_before_m);
    out.validation_rms_after = recording::AsWritten(result.validation.rms_after_m);
    out.validation_matches_before = result.validation.matches_before;
    out.validation_matches_after = result.validation.matches_after;
  }
  if (!result.parameters.empty()) {
    out.predicted_error = recording::AsWritten(result.predicted.sensor.rms_position_m);
    out.predicted_worst_error = recording::AsWritten(result.predicted.sensor.max_position_m);
    if (result.predicted_held.samples > 0)
      out.predicted_held_error = recording::AsWritten(result.predicted_held.sensor.rms_position_m);
  }
  if (!result.held_out.scans.empty()) {
    out.held_out_offset = recording::AsWritten(result.held_out.rms_position_m);
    out.held_out_worst_offset = recording::AsWritten(result.held_out.worst_position_m);
  }
  out.unobservable = result.unobservable;
  return out;
}

Expected<std::unique_ptr<CalibrationEngine>> MakeDefaultEngine() {
  return std::unique_ptr<CalibrationEngine>(std::make_unique<CalibEngine>());
}

}  // namespace selfcal::daemon
