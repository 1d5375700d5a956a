// What the engine's single-purpose benches (cost_at_truth, held_out_check, nearest_floor) load:
// a model file, a sensor file and a recording read with them, and the sensor's engine options.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/calib/calibrate.h"
#include "core/calib/chain.h"
#include "core/calib/pose_knots.h"
#include "protocols/model_file/model_file.h"
#include "protocols/model_file/sensor_config.h"

namespace selfcal::bench {

struct BenchRecording {
  ModelFile model;
  SensorConfig sensor;
  std::vector<calib::Dataset> datasets;
  calib::CalibrationOptions options;  // CalibrationOptionsFromSensor(sensor)
};

// Reads the three files; `fit_scans`, when not null, caps the fit scans read. On an error prints
// it (it names the file) to stderr and returns nothing.
std::optional<BenchRecording> LoadBenchRecording(const std::string& model_path,
                                                 const std::string& sensor_path,
                                                 const std::string& recording_path,
                                                 const char* fit_scans);

// What the engine starts from for a recording at its model, as Calibrate() does: the
// normalization scale, the chain, the normalized parameters, every scan's knots, the fit scans.
struct EngineStart {
  double scale = 0;
  calib::Chain chain;
  std::vector<double> k_hat;
  std::vector<calib::PoseKnots> knots;
  std::vector<bool> fit;
};
EngineStart StartEngine(const BenchRecording& recording, int threads);

}  // namespace selfcal::bench
