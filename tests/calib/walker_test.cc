// A scan with a person walking through calibrates as well as without (within 10 %): the small room
// corner (tests/calib/data/small-walker.yaml, 14 + 7 scans of a Kinect-like camera at 80 x 72)
// with a person in fit scan 5, and the same recording without the person (the same noise draws),
// calibrated from the nominal model 30 mm off, with the paper's squared loss and with the robust
// one (docs/engine.md deviation 14), on two seeds: the sensor pose error with the person is at
// most 10 % above the error without. d_max does most of the work: the person stands more than
// 20 mm in front of what the other scans see, but for a thin band where it touches the wall.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/calib/calibrate.h"
#include "core/model/evaluation.h"
#include "tests/calib/simulated_scenario.h"

namespace selfcal::calib {
namespace {

using simulated::Recording;
using simulated::SourceDir;

class Walker : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ = simulated::TemporaryFolder("walker");
    std::filesystem::create_directories(directory_);
    // The same scenario without the person: an empty scan list keeps the field simulation (and
    // so its noise draws) and draws no capsule.
    std::ifstream in(SourceDir() + "/tests/calib/data/small-walker.yaml");
    std::stringstream text;
    text << in.rdbuf();
    std::string without = text.str();
    const std::size_t at = without.find("scans: [5]");
    ASSERT_NE(at, std::string::npos);
    without.replace(at, 10, "scans: []");
    // Relative paths in the scenario are resolved from its folder: write it beside the original's.
    std::ofstream(directory_ / "small-no-walker.yaml") << ReplaceRelative(without);
  }
  void TearDown() override { std::filesystem::remove_all(directory_); }

  static std::string ReplaceRelative(std::string text) {
    const std::string from = "../../../config/";
    const std::string to = SourceDir() + "/config/";
    for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at)) {
      text.replace(at, from.size(), to);
      at += to.size();
    }
    return text;
  }

  Recording Simulate(const std::string& scenario, int seed, const std::string& name) {
    const std::filesystem::path out = directory_ / (name + std::to_string(seed));
    EXPECT_TRUE(simulated::Simulate(scenario, out, "--seed " + std::to_string(seed))) << scenario;
    auto recording =
        simulated::Read(out, SourceDir() + "/config/sensors/kinect_azure_nfov_binned.yaml");
    EXPECT_TRUE(recording.ok()) << (recording.ok() ? "" : recording.error().message);
    return recording.ok() ? std::move(*recording) : Recording{};
  }

  // Sensor position error RMS [m] over 500 configurations after calibrating from the nominal.
  double CalibratedError(const Recording& recording, LossKind loss) {
    CalibrationOptions options = recording.options;
    options.loss = loss;
    const CalibrationResult result = Calibrate(recording.datasets, recording.nominal, options);
    EXPECT_TRUE(result.converged) << result.message;
    return SensorPoseError(recording.truth, result.model, 500, 42).rms_position_m;
  }

  std::filesystem::path directory_;
};

// Pixels of the scan where the person stands that moved by more than 5 cm (the person and the
// parts of the room that it hides): the person is in view.
std::size_t PixelsThePersonChanged(const Recording& with, const Recording& without) {
  std::size_t most = 0;
  for (std::size_t d = 0; d < with.datasets.size() && d < without.datasets.size(); ++d) {
    const Dataset& a = with.datasets[d];
    const Dataset& b = without.datasets[d];
    std::size_t changed = 0;
    for (std::size_t i = 0; i < a.PointCount() && i < b.PointCount(); ++i) {
      const bool valid_a = a.IsValid(i), valid_b = b.IsValid(i);
      if (valid_a != valid_b) {
        ++changed;
      } else if (valid_a && std::abs(a.z[i] - b.z[i]) > 0.05f) {
        ++changed;
      }
    }
    most = std::max(most, changed);
  }
  return most;
}

TEST_F(Walker, APersonInOneScanCostsAtMostTenPercent) {
  for (int seed : {1, 2}) {
    const Recording with =
        Simulate(SourceDir() + "/tests/calib/data/small-walker.yaml", seed, "with");
    const Recording without =
        Simulate((directory_ / "small-no-walker.yaml").string(), seed, "without");
    ASSERT_FALSE(with.datasets.empty() || without.datasets.empty());
    const std::size_t changed = PixelsThePersonChanged(with, without);
    EXPECT_GT(changed, 300u) << "the person is not in view";
    for (LossKind loss : {LossKind::kSquared, LossKind::kCauchy}) {
      const double error_with = CalibratedError(with, loss);
      const double error_without = CalibratedError(without, loss);
      std::printf(
          "seed %d, loss %s: the person changes %zu pixels; sensor position %.4f mm with, %.4f mm "
          "without\n",
          seed, LossName(loss), changed, error_with * 1e3, error_without * 1e3);
      EXPECT_LE(error_with, 1.10 * error_without) << "seed " << seed << ", " << LossName(loss);
    }
  }
}

}  // namespace
}  // namespace selfcal::calib
