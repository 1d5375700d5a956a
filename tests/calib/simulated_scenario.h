// What the engine's tests on a simulated scenario share: the scenario simulated by the real
// `selfcal simulate` (SELFCAL_BINARY) into a folder of its own, and read back as the engine gets
// it (nominal and true models, the recording's datasets, the sensor file's options), so every
// test calibrates exactly what `selfcal calibrate` would.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "core/calib/calibrate.h"
#include "protocols/model_file/model_file.h"
#include "protocols/model_file/sensor_config.h"
#include "protocols/recording/recording.h"

namespace selfcal::calib::simulated {

// The source tree (ctest sets SELFCAL_SOURCE_DIR), for scenario and sensor files.
inline std::string SourceDir() {
  const char* source = std::getenv("SELFCAL_SOURCE_DIR");
  return source != nullptr ? source : ".";
}

// A folder in the temporary directory for this process and `tag`.
inline std::filesystem::path TemporaryFolder(const std::string& tag) {
  return std::filesystem::temp_directory_path() /
         ("selfcal_" + tag + "_" + std::to_string(getpid()));
}

// `selfcal -q simulate SCENARIO --threads 2 --out OUT EXTRA`; true when it succeeded.
inline bool Simulate(const std::string& scenario, const std::filesystem::path& out,
                     const std::string& extra = "") {
  const std::string command = std::string(SELFCAL_BINARY) + " -q simulate " + scenario +
                              " --threads 2 --out " + out.string() + " " + extra;
  return std::system(command.c_str()) == 0;
}

struct Recording {
  RobotModel nominal, truth;
  SensorConfig sensor;
  CalibrationOptions options;  // the sensor file's, on 2 threads
  std::vector<Dataset> datasets;
};

// What `selfcal simulate` wrote to `folder`, read with the sensor file `sensor`.
inline Expected<Recording> Read(const std::filesystem::path& folder, const std::string& sensor,
                                const recording::RecordingOptions& reading = {}) {
  auto nominal = ReadModelFile((folder / "nominal.yaml").string());
  if (!nominal) return nominal.error();
  auto truth = ReadModelFile((folder / "truth.yaml").string());
  if (!truth) return truth.error();
  auto sensor_config = ReadSensorConfig(sensor);
  if (!sensor_config) return sensor_config.error();
  const CalibrationOptions options = recording::CalibrationOptionsFromSensor(*sensor_config);
  recording::RecordingOptions timed = reading;
  timed.joint_timing |= options.estimate_latency;  // a sweeping sensor's latency (deviation 16)
  auto datasets = recording::LoadRecording((folder / "recording.lcmlog").string(), nominal->model,
                                           *sensor_config, timed);
  if (!datasets) return datasets.error();
  Recording simulated{nominal->model, truth->model, *sensor_config, options, std::move(*datasets)};
  simulated.options.threads = 2;
  return simulated;
}

// A test suite on one simulated scenario, simulated once for the whole suite:
//   class Suite : public simulated::ScenarioTest<Suite> {
//     static constexpr const char* kScenario = "tests/calib/data/x.yaml";  // in the source tree
//     static constexpr const char* kSensor = "config/sensors/y.yaml";
//     static constexpr const char* kTag = "x";  // names the temporary folder
//     static recording::RecordingOptions Reading();  // optional: how to read the recording
//   };
// Each test starts with the recording in nominal_, truth_, options_ and datasets_.
template <typename Suite>
class ScenarioTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    Folder() = TemporaryFolder(Suite::kTag);
    Succeeded() = Simulate(SourceDir() + "/" + Suite::kScenario, Folder());
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(Folder()); }
  void SetUp() override {
    ASSERT_TRUE(Succeeded()) << "selfcal simulate " << Suite::kScenario << " failed";
    auto read = Read(Folder(), SourceDir() + "/" + Suite::kSensor, Suite::Reading());
    ASSERT_TRUE(read.ok()) << read.error().message;
    nominal_ = read->nominal;
    truth_ = read->truth;
    options_ = read->options;
    datasets_ = std::move(read->datasets);
  }
  static recording::RecordingOptions Reading() { return {}; }
  static std::filesystem::path& Folder() {
    static std::filesystem::path folder;
    return folder;
  }
  static bool& Succeeded() {
    static bool succeeded = false;
    return succeeded;
  }

  RobotModel nominal_, truth_;
  CalibrationOptions options_;
  std::vector<Dataset> datasets_;
};

}  // namespace selfcal::calib::simulated
