// What changed, on simulated recordings through the command line: the small scenario's truth is
// the arm as it is now, the installed model is that truth before a lost zero (A4 0.5 deg), a
// bumped mount (4 mm, 0.5 deg), a longer link (A3 -> A4, 3 mm) or nothing, and
// `selfcal calibrate --robot INSTALLED` (a full calibration) must name that change and no other
// class in its result's `change:` section and its output.
#include "core/model/model_change.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <string>

#include "core/model/joint_offsets.h"
#include "protocols/model_file/model_file.h"
#include "tests/calib/simulated_scenario.h"

namespace selfcal {
namespace {

constexpr double kDegree = M_PI / 180;

using calib::simulated::SourceDir;

class ModelChangeOnRecordings : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    directory_ = calib::simulated::TemporaryFolder("model_change");
    ASSERT_TRUE(calib::simulated::Simulate(SourceDir() + "/config/scenarios/small.yaml", directory_,
                                           "--seed 1"));
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(directory_); }

  RobotModel Truth() {
    auto truth = ReadModelFile((directory_ / "truth.yaml").string());
    EXPECT_TRUE(truth) << truth.error().message;
    return truth->model;
  }

  // The findings' numbers are the fit's between the installed and the result's model (repeated
  // here: the fit does not depend on the covariance, which only sets the standard deviations), in
  // the units of their texts; the calibration's covariance gives every deviation.
  static void CheckFindingNumbers(const RobotModel& installed, const std::string& result_path,
                                  const YAML::Node& findings) {
    const auto calibrated = ReadModelFile(result_path);
    ASSERT_TRUE(calibrated) << calibrated.error().message;
    const JointOffsetFit fit = DescribeModelChange(installed, calibrated->model, {}, {}).fit;
    const auto expect = [&](const YAML::Node& finding, const std::string& key, double value) {
      ASSERT_TRUE(finding[key]) << key << " missing in " << finding;
      EXPECT_NEAR(finding[key].as<double>(), value, 1e-5) << key << " in " << finding;
      const std::string unit = key.substr(key.rfind('_'));
      const YAML::Node std_dev = finding[key.substr(0, key.rfind('_')) + "_std_dev" + unit];
      ASSERT_TRUE(std_dev && std_dev.IsScalar()) << finding;
      EXPECT_GT(std_dev.as<double>(), 0) << finding;
    };
    for (const auto& finding : findings) {
      const std::string kind = finding["kind"].as<std::string>();
      if (kind == "joint_zero") {
        const auto& joints = calibrated->model.joints;
        const auto j = std::find_if(joints.begin(), joints.end(),
                                    [&](const JointSpec& joint) {
                                      return joint.name == finding["joint"].as<std::string>();
                                    }) -
                       joints.begin();
        ASSERT_LT(static_cast<std::size_t>(j), joints.size()) << finding;
        expect(finding, "moved_deg", fit.offsets[static_cast<std::size_t>(j)] / kDegree);
      } else if (kind == "sensor_mount") {
        expect(finding, "shift_mm", fit.mount_shift_m * 1e3);
        expect(finding, "turn_deg", fit.mount_turn_rad / kDegree);
      } else {
        expect(finding, "unexplained_rms_mm", fit.rms_position_m * 1e3);
      }
    }
  }

  // Calibrates from `installed`; the kinds of the result's findings, and the output in `output`.
  std::multiset<std::string> Kinds(const std::string& name, const RobotModel& installed,
                                   std::string& output) {
    const std::string installed_path = (directory_ / (name + "_installed.yaml")).string();
    EXPECT_TRUE(WriteModelFile(installed_path, installed, ""));
    const std::string out = (directory_ / (name + "_result.yaml")).string();
    const std::string calibrate =
        std::string(SELFCAL_BINARY) + " -q calibrate --robot " + installed_path + " --sensor " +
        SourceDir() + "/config/sensors/kinect_azure_nfov_binned.yaml --log " +
        (directory_ / "recording.lcmlog").string() + " --threads 2 --out " + out + " 2>&1";
    FILE* pipe = popen(calibrate.c_str(), "r");
    char buffer[512];
    while (pipe && std::fgets(buffer, sizeof buffer, pipe) != nullptr) output += buffer;
    const int status = pipe ? pclose(pipe) : -1;
    EXPECT_TRUE(WIFEXITED(status)) << calibrate << "\n" << output;
    std::multiset<std::string> kinds;
    const YAML::Node change = YAML::LoadFile(out)["calibration"]["change"];
    EXPECT_TRUE(change.IsMap()) << out;
    for (const auto& finding : change["findings"]) kinds.insert(finding["kind"].as<std::string>());
    CheckFindingNumbers(installed, out, change["findings"]);
    EXPECT_NE(output.find("what changed against the --robot model: " +
                          change["summary"].as<std::string>()),
              std::string::npos)
        << output;
    return kinds;
  }

  static std::filesystem::path directory_;
};
std::filesystem::path ModelChangeOnRecordings::directory_;

TEST_F(ModelChangeOnRecordings, ALostZeroIsAJointZeroOffset) {
  // The arm reads q where A4 stands at q + 0.5 deg: installed(q + offset) = truth(q).
  auto installed = WithJointOffsets(Truth(), {0, 0, 0, -0.5 * kDegree, 0, 0, 0});
  ASSERT_TRUE(installed);
  std::string output;
  EXPECT_EQ(Kinds("zero", *installed, output), std::multiset<std::string>{"joint_zero"}) << output;
  EXPECT_NE(output.find("joint A4 zero offset moved 0.5"), std::string::npos) << output;
}

TEST_F(ModelChangeOnRecordings, ABumpedMountIsTheSensorMount) {
  RobotModel installed = Truth();
  installed.tool.x -= 0.004;
  installed.tool.alpha -= 0.5 * kDegree;
  std::string output;
  EXPECT_EQ(Kinds("mount", installed, output), std::multiset<std::string>{"sensor_mount"})
      << output;
}

TEST_F(ModelChangeOnRecordings, ALongerLinkIsLinkGeometry) {
  RobotModel installed = Truth();
  installed.segments[2].y -= 0.003;
  std::string output;
  EXPECT_EQ(Kinds("link", installed, output).count("link_geometry"), 1u) << output;
}

TEST_F(ModelChangeOnRecordings, NothingChangedIsNoSignificantChange) {
  std::string output;
  EXPECT_TRUE(Kinds("none", Truth(), output).empty()) << output;
  EXPECT_NE(output.find("what changed against the --robot model: no significant change"),
            std::string::npos)
      << output;
}

}  // namespace
}  // namespace selfcal
