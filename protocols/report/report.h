// A session's report: one self-contained HTML file (no network needed to open it) for the
// technician who triggered the calibration and the engineer who looks after the robot. It shows
// what changed against the old model (each finding with its numbers), the held-out validation
// scans fused with the old and the new model side by side in 3D (three.js, as the paper's
// Figures 5 and 6), the validation residuals before and after, the convergence per iteration, the
// scans' joint-space coverage against the limits, the predicted error map, the parameter changes
// with their standard deviations (Chart.js), the acceptance gate's decision with its rules and
// numbers, the software and how to roll back. docs/report.md.
//
// The JavaScript libraries are Debian's (libjs-three, libjs-chart.js), read from
// ReportOptions::javascript_folder when the report is written and inlined with their licences.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/calib/calibrate.h"
#include "core/calib/dataset.h"
#include "core/model/robot_model.h"
#include "core/util/expected.h"
#include "protocols/model_file/sensor_config.h"
#include "protocols/recording/recording.h"

namespace selfcal::report {

// One rule of the acceptance gate, as the report lists it: its bound and this session's number
// (the gate describes its own rules: daemon/gate_rules.h).
struct GateRule {
  std::string rule;
  std::string limit;
  std::string measured;
};

// The gate's decision as the daemon (or `selfcal report`, with the daemon's gate) made it.
struct GateSummary {
  bool accepted = false;
  std::string reason;         // the gate's own words, with its numbers
  std::string configuration;  // where the bounds come from, e.g. "/etc/selfcal/daemon.yaml"
  std::vector<GateRule> rules;
};

struct ReportInput {
  std::string title;                    // e.g. "session 20261202-061500" or the result file's path
  std::string software;                 // "selfcal 0.1.0"
  std::string before_name, after_name;  // where the models come from
  RobotModel before, after;
  std::string calibration_yaml;  // the result's `calibration:` section (a YAML mapping)
  std::string recording_name;
  std::vector<calib::Dataset> datasets;  // the recording's scans, fit and validation
  calib::CalibrationOptions options;     // the sensor's matching parameters (residuals)
  GateSummary gate;
  std::string rollback;  // how to go back to the old model, in words
};

struct ReportOptions {
  std::size_t max_points_per_model = 150'000;  // of the validation scans, every n-th point
  std::string javascript_folder = "/usr/share/javascript";
  std::string licence_folder = "/usr/share/doc";
};

// The page. Errors: a missing JavaScript library (names the Debian package), a calibration
// section that is not a YAML mapping.
Expected<std::string> FormatReport(const ReportInput& input, const ReportOptions& options = {});

// FormatReport, written atomically.
Status WriteReport(const std::string& path, const ReportInput& input,
                   const ReportOptions& options = {});

// Reads the recording as the engine does (`sensor` picks the channels' messages and the matching
// parameters) into `input.datasets` and `input.options`.
Status LoadRecordingInto(ReportInput& input, const std::string& recording_path,
                         const SensorConfig& sensor, const recording::RecordingOptions& options);

}  // namespace selfcal::report
