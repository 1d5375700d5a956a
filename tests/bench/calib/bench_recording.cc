#include "tests/bench/calib/bench_recording.h"

#include <cstdio>

#include "core/calib/pair_information.h"
#include "core/model/normalization.h"
#include "protocols/recording/recording.h"

namespace selfcal::bench {

std::optional<BenchRecording> LoadBenchRecording(const std::string& model_path,
                                                 const std::string& sensor_path,
                                                 const std::string& recording_path,
                                                 const char* fit_scans) {
  auto fail = [](const Error& error) {
    std::fprintf(stderr, "%s\n", error.message.c_str());
    return std::nullopt;
  };
  auto model = ReadModelFile(model_path);
  if (!model) return fail(model.error());
  auto sensor = ReadSensorConfig(sensor_path);
  if (!sensor) return fail(sensor.error());
  recording::RecordingOptions recording_options;
  if (fit_scans != nullptr) recording_options.max_fit_scans = std::stoi(fit_scans);
  auto datasets =
      recording::LoadRecording(recording_path, model->model, *sensor, recording_options);
  if (!datasets) return fail(datasets.error());
  calib::CalibrationOptions options = recording::CalibrationOptionsFromSensor(*sensor);
  return BenchRecording{std::move(*model), std::move(*sensor), std::move(*datasets), options};
}

EngineStart StartEngine(const BenchRecording& recording, int threads) {
  const RobotModel& model = recording.model.model;
  EngineStart start;
  start.scale = calib::EngineScale(recording.datasets, model);
  start.chain = calib::ChainOf(model, start.scale);
  start.k_hat = ToParameterVector(model);
  NormalizeTranslationParameters(start.k_hat, model.JointCount(), start.scale);
  start.knots = calib::BuildAllPoseKnots(recording.datasets, threads);
  for (const calib::Dataset& dataset : recording.datasets) start.fit.push_back(!dataset.validation);
  return start;
}

}  // namespace selfcal::bench
