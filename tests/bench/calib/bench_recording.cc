#include "tests/bench/calib/bench_recording.h"

#include <cstdio>

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

}  // namespace selfcal::bench
