// Recordings (LCM logs, docs/recording.md) -> datasets for the calibration engine.
// The daemon and `selfcal calibrate` call this; keep it stable.
//
// Every error names the scan (by scan_index) and what is wrong: missing or too few joint states
// around a measurement, a wrong joint count, NaN or infinite joint values, a scan without valid
// points, markers that do not pair up, sensor messages of the wrong shape.
#pragma once

#include <string>
#include <vector>

#include "core/calib/calibrate.h"
#include "core/calib/dataset.h"
#include "core/model/robot_model.h"
#include "core/util/expected.h"
#include "protocols/model_file/sensor_config.h"
#include "protocols/recording/provenance.h"

namespace selfcal::recording {

struct RecordingOptions {
  // The sensor's latency relative to the joint states [s]: joints are interpolated to
  // measurement time + latency.
  double latency_s = 0.0;
  // Both joint states around a measurement must lie within this time of it [s].
  double max_joint_gap_s = 0.050;
  // Fit scans to keep, in scan_index order (0 = all). Validation scans are always kept.
  int max_fit_scans = 0;
  // Channels (defaults: protocols/lcm/channels.h).
  std::string joint_state_channel = "SELFCAL_JOINT_STATE";
  std::string scan_marker_channel = "SELFCAL_SCAN_MARKER";
  std::string range_scan_channel = "SELFCAL_RANGE_SCAN";
  std::string line_profile_channel = "SELFCAL_LINE_PROFILE";
  std::string depth_image_channel = "SELFCAL_DEPTH_IMAGE";
  std::string organized_cloud_channel = "SELFCAL_ORGANIZED_CLOUD";
};

// Reads the log at `path` and assembles one dataset per scan, in scan_index order. `robot`
// gives the joint count and names (joint states must list the model's joints in its order);
// `sensor.layout` selects the sensor channel(s) and the grid layout.
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

}  // namespace selfcal::recording
