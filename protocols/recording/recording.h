// Recordings (LCM logs, docs/recording.md) -> datasets for the calibration engine.
// The daemon and `selfcal calibrate` call this; keep it stable.
//
// Every error names the scan (by scan_index) and what is wrong: missing or too few joint states
// around a measurement, a wrong joint count or joint names, NaN or infinite joint values, a scan
// without valid points or without sensor messages (and what the log has instead), markers that do
// not pair up, sensor messages of the wrong shape or of another sensor, a log that ends early.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/calib/calibrate.h"
#include "core/calib/dataset.h"
#include "core/model/robot_model.h"
#include "core/util/expected.h"
#include "protocols/lcm/channels.h"
#include "protocols/model_file/sensor_config.h"
#include "protocols/recording/provenance.h"

namespace selfcal::recording {

struct RecordingOptions {
  // The sensor's latency relative to the joint states [s]: joints are interpolated to
  // measurement time + latency. Unset: the sensor file's (latency: seconds, else 0).
  std::optional<double> latency_s;
  // Also keep every pose's measurement time and the joint states (Dataset::pose_utime,
  // joint_states), which the engine's latency estimate re-interpolates
  // (CalibrationOptions::estimate_latency). Off: a double per pose and the joint states more.
  bool joint_timing = false;
  // Which recording of a calibration this is (Dataset::recording: one latency each).
  int recording = 0;
  // Both joint states around a measurement must lie within this time of it [s].
  double max_joint_gap_s = 0.050;
  // Fit scans to keep, in scan_index order (0 = all). Validation scans are always kept.
  int max_fit_scans = 0;
  // A log that ends early (cut off, or still being written: a torn last event, a last scan with
  // a BEGIN marker but no END) is an error that says so; with this set, its complete scans are
  // used and Recording::incomplete says what was left out.
  bool allow_incomplete = false;
  channels::RecordingChannels channels;

  // Reads the sensor of `layout` from `channel` (the daemon records one sensor channel): the
  // range scan, line profile, or depth image and organized cloud channel.
  void SetSensorChannel(SensorLayout layout, const std::string& channel);
};

// A recording's datasets and what the reader noticed on the way.
struct Recording {
  std::vector<calib::Dataset> datasets;  // one per complete scan, in scan_index order
  // Empty for a complete log; else how it ends early (only with allow_incomplete).
  std::string incomplete;
  // Where the data does not look like the sensor file's sensor (docs/formats.md, "Sensor file"):
  // binned frames, other intrinsics, other rays, points outside the view range.
  std::vector<std::string> warnings;
};

// Reads the log at `path` and assembles one dataset per scan, in scan_index order. `robot`
// gives the joint count and names (joint states must name the model's joints in its order);
// `sensor.layout` selects the sensor channel(s) and the grid layout; the frames must have the
// sensor file's resolution or a binning of it.
Expected<Recording> ReadRecording(const std::string& path, const RobotModel& robot,
                                  const SensorConfig& sensor, const RecordingOptions& options = {});

// ReadRecording's datasets, for callers that have no use for its warnings.
Expected<std::vector<calib::Dataset>> LoadRecording(const std::string& path,
                                                    const RobotModel& robot,
                                                    const SensorConfig& sensor,
                                                    const RecordingOptions& options = {});

// The engine's per-sensor parameters (Table I) from a sensor file.
calib::CalibrationOptions CalibrationOptionsFromSensor(const SensorConfig& sensor);

// The `calibration:` section of a result model file (a YAML mapping, docs/formats.md "Result
// file"): provenance when given, termination, iterations, matches per iteration, runtime,
// validation before/after, per-parameter values and std dev, poorly observable parameters.
std::string FormatCalibrationYaml(const calib::CalibrationResult& result,
                                  const Provenance* provenance = nullptr);
// A length [m] or an angle [rad] as FormatCalibrationYaml writes it and a reader gets it back
// (9 decimals). What the gate judges goes through it, so that a report judged again from the
// file decides and words it as `selfcal calibrate` and selfcald did, to the last digit.
double AsWritten(double value);

}  // namespace selfcal::recording
