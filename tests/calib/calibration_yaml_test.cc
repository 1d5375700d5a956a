// The result file's `calibration:` section: units in the keys, numbers rounded to what they mean,
// no "-0", and provenance with content hashes.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "protocols/recording/provenance.h"
#include "protocols/recording/recording.h"

namespace selfcal::recording {
namespace {

calib::CalibrationResult SmallResult() {
  calib::CalibrationResult result;
  result.runtime_s = 12.3456789;
  result.scale_m = 1.19902703812;
  result.validation.available = true;
  result.validation.rms_before_m = 0.0093364732153;
  result.validation.rms_after_m = 0.00525686607;
  calib::IterationReport iteration;
  iteration.rms_before_m = 0.009508915305;
  iteration.rms_after_m = 0.006346956804;
  iteration.delta = 4.210198584e-05;
  iteration.seconds = 0.444365462;
  result.iterations.push_back(iteration);
  iteration.noise_fraction = 0.65354410;  // --noise-correction's share (deviation 23)
  result.iterations.push_back(iteration);
  result.parameters.push_back({"A7->tool.alpha", -0.0, -1.2e-12, 8.863996071e-05});
  result.parameters.push_back({"A7->tool.z", 0.201, 0.19489592891234, 1.981381544e-04});
  return result;
}

TEST(CalibrationYaml, KeysCarryUnitsAndNumbersAreRounded) {
  const std::string text = FormatCalibrationYaml(SmallResult());
  const YAML::Node yaml = YAML::Load(text);
  EXPECT_EQ(yaml["runtime_s"].as<std::string>(), "12.346");
  EXPECT_EQ(yaml["scale_m"].as<std::string>(), "1.199027038");
  EXPECT_EQ(yaml["validation"]["rms_before_m"].as<std::string>(), "0.009336473");
  const YAML::Node iteration = yaml["per_iteration"][0];
  EXPECT_EQ(iteration["rms_after_m"].as<std::string>(), "0.006346957");
  EXPECT_EQ(iteration["delta_k"].as<std::string>(), "0.000042102");
  EXPECT_EQ(iteration["time_s"].as<std::string>(), "0.444");
  EXPECT_FALSE(iteration["noise_fraction"]) << "no key without the noise correction";
  EXPECT_EQ(yaml["per_iteration"][1]["noise_fraction"].as<std::string>(), "0.6535");
  const YAML::Node angle = yaml["parameters"][0];
  EXPECT_EQ(angle["nominal_rad"].as<std::string>(), "0");     // -0.0 is written as 0
  EXPECT_EQ(angle["calibrated_rad"].as<std::string>(), "0");  // -1.2e-12 rounds to 0, not -0
  EXPECT_EQ(angle["std_dev_rad"].as<std::string>(), "0.00008864");
  const YAML::Node length = yaml["parameters"][1];
  EXPECT_EQ(length["calibrated_m"].as<std::string>(), "0.194895929");
  EXPECT_FALSE(length["calibrated_rad"]);
  EXPECT_EQ(text.find("-0,"), std::string::npos) << text;
  EXPECT_EQ(text.find("e-"), std::string::npos) << "no exponents: " << text;
  EXPECT_FALSE(yaml["software"]) << "no provenance unless given";
}

// What the gate judges is what the file holds: found when `selfcal calibrate` printed a validation
// RMS of 5.34448 mm (from 0.0053444849 m) and the report, judging again from the file's
// 0.005344485, printed 5.34449 mm.
TEST(CalibrationYaml, AsWrittenIsWhatAReaderGetsBack) {
  calib::CalibrationResult result = SmallResult();
  result.validation.rms_after_m = 0.0053444849;
  const YAML::Node yaml = YAML::Load(FormatCalibrationYaml(result));
  const double read = yaml["validation"]["rms_after_m"].as<double>();
  EXPECT_EQ(AsWritten(result.validation.rms_after_m), read);
  EXPECT_EQ(read, 0.005344485);
  EXPECT_EQ(AsWritten(-1.2e-12), 0.0);
  EXPECT_TRUE(std::isinf(AsWritten(INFINITY)));
  EXPECT_TRUE(std::isnan(AsWritten(NAN)));
}

// The predicted error map: one row per joint with its unit in the keys, the worst regions after.
TEST(CalibrationYaml, PredictedErrorMapPerJointAndWorstRegions) {
  calib::CalibrationResult result = SmallResult();
  calib::JointErrorProfile rail{"rail",
                                true,
                                0.0,
                                0.6,
                                {1, 0, 2, 3, 4, 5},
                                {1e-3, 0, 2e-3, 3e-3, 4e-3, 5.0000000004e-3},
                                {1e-4, 0, 2e-4, 3e-4, 4e-4, 5e-4}};
  calib::JointErrorProfile wrist{"A7",
                                 false,
                                 -3.054,
                                 3.054,
                                 {6, 5, 4, 3, 2, 1},
                                 {1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3},
                                 {1e-4, 1e-4, 1e-4, 1e-4, 1e-4, 1e-4}};
  result.predicted.map.joints = {rail, wrist};
  result.predicted.map.worst = {{0, 5, 0.5, 0.6, 5e-3}, {1, 0, -3.054, -2.036, 1e-3}};
  const YAML::Node yaml = YAML::Load(FormatCalibrationYaml(result));
  const YAML::Node predicted = yaml["predicted_error"];
  EXPECT_EQ(predicted["bins"].as<std::size_t>(), calib::kErrorMapBins);
  const YAML::Node first = predicted["map"][0];
  EXPECT_EQ(first["joint"].as<std::string>(), "rail");
  EXPECT_EQ(first["upper_m"].as<std::string>(), "0.6");
  EXPECT_FALSE(first["upper_rad"]);
  EXPECT_EQ(first["samples"][3].as<std::size_t>(), 3u);
  EXPECT_EQ(first["sensor_rms_position_m"][5].as<std::string>(), "0.005");
  EXPECT_EQ(first["flange_rms_position_m"][2].as<std::string>(), "0.0002");
  EXPECT_EQ(predicted["map"][1]["lower_rad"].as<std::string>(), "-3.054");
  const YAML::Node worst = predicted["worst_regions"];
  ASSERT_EQ(worst.size(), 2u);
  EXPECT_EQ(worst[0]["joint"].as<std::string>(), "rail");
  EXPECT_EQ(worst[0]["lower_m"].as<std::string>(), "0.5");
  EXPECT_EQ(worst[0]["samples"].as<std::size_t>(), 5u);
  EXPECT_EQ(worst[1]["joint"].as<std::string>(), "A7");
  EXPECT_EQ(worst[1]["upper_rad"].as<std::string>(), "-2.036");
  EXPECT_EQ(worst[1]["sensor_rms_position_m"].as<std::string>(), "0.001");
}

TEST(CalibrationYaml, NonFiniteStdDevIsYamlInfinity) {
  calib::CalibrationResult result = SmallResult();
  result.parameters[0].std_dev = std::numeric_limits<double>::infinity();
  const YAML::Node yaml = YAML::Load(FormatCalibrationYaml(result));
  EXPECT_TRUE(std::isinf(yaml["parameters"][0]["std_dev_rad"].as<double>()));
}

// What changed carries its numbers beside the technician's text: per finding in deg or mm, the
// units of the text, with the standard deviation (null without a covariance).
TEST(CalibrationYaml, ChangeFindingsCarryTheirNumbersInDegreesAndMillimetres) {
  calib::CalibrationResult result = SmallResult();
  result.model.joints = {{"A4", JointType::kRevolute}, {"rail", JointType::kPrismatic}};
  result.change_known = true;
  result.change.fit.offsets = {0.0071558499, 0.0012345678};
  const auto& offsets = result.change.fit.offsets;
  result.change.findings = {
      {ChangeKind::kJointZero, "A4", offsets[0], 0, 8.7266e-5, 0, "joint A4 moved"},
      {ChangeKind::kJointZero, "rail", offsets[1], 0, 0, 0, "joint rail moved"},
      {ChangeKind::kSensorMount, "", 0.0021234567891, 0.0052359877, 4.1e-5, 3.3e-5, "mount"},
      {ChangeKind::kLinkGeometry, "", 0.00023456789, 0, 1.5e-5, 0, "links"}};
  const YAML::Node findings = YAML::Load(FormatCalibrationYaml(result))["change"]["findings"];
  ASSERT_EQ(findings.size(), result.change.findings.size());
  const auto near = [](const YAML::Node& node, double expected, double rounding) {
    EXPECT_NEAR(node.as<double>(), expected, rounding / 2 * (1 + 1e-9)) << node;
  };
  const double degrees = 180 / M_PI;
  EXPECT_EQ(findings[0]["kind"].as<std::string>(), "joint_zero");
  EXPECT_EQ(findings[0]["joint"].as<std::string>(), "A4");
  near(findings[0]["moved_deg"], offsets[0] * degrees, 1e-8);
  near(findings[0]["moved_std_dev_deg"], 8.7266e-5 * degrees, 1e-8);
  EXPECT_EQ(findings[0]["text"].as<std::string>(), "joint A4 moved");
  // A prismatic joint's zero moves in mm; without a covariance its deviation is null.
  EXPECT_FALSE(findings[1]["moved_deg"]);
  near(findings[1]["moved_mm"], offsets[1] * 1e3, 1e-6);
  ASSERT_TRUE(findings[1]["moved_std_dev_mm"]);
  EXPECT_TRUE(findings[1]["moved_std_dev_mm"].IsNull());
  EXPECT_EQ(findings[2]["kind"].as<std::string>(), "sensor_mount");
  EXPECT_FALSE(findings[2]["joint"]);
  near(findings[2]["shift_mm"], 2.1234567891, 1e-6);
  near(findings[2]["shift_std_dev_mm"], 0.041, 1e-6);
  near(findings[2]["turn_deg"], 0.0052359877 * degrees, 1e-8);
  near(findings[2]["turn_std_dev_deg"], 3.3e-5 * degrees, 1e-8);
  EXPECT_EQ(findings[3]["kind"].as<std::string>(), "link_geometry");
  near(findings[3]["unexplained_rms_mm"], 0.23456789, 1e-6);
  near(findings[3]["unexplained_rms_std_dev_mm"], 0.015, 1e-6);
}

TEST(Provenance, HashesInputsAndNamesTheCommandLine) {
  const auto path = std::filesystem::temp_directory_path() / "selfcal_provenance_test.txt";
  std::ofstream(path) << "abc";
  // SHA-256("abc"), FIPS 180-2 appendix B.1.
  EXPECT_EQ(*FileSha256(path.string()),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  const auto provenance = MakeProvenance("selfcal test", {{"robot", path.string()}});
  ASSERT_TRUE(provenance);
  const YAML::Node yaml = YAML::Load(FormatCalibrationYaml(SmallResult(), &*provenance));
  EXPECT_EQ(yaml["software"].as<std::string>(), "selfcal test");
  EXPECT_NE(yaml["command_line"].as<std::string>().find("calibration_yaml_test"),
            std::string::npos);
  EXPECT_EQ(yaml["inputs"][0]["role"].as<std::string>(), "robot");
  EXPECT_EQ(yaml["inputs"][0]["sha256"].as<std::string>().substr(0, 8), "ba7816bf");
  std::filesystem::remove(path);

  const auto missing = MakeProvenance("selfcal test", {{"robot", "/nonexistent/robot.yaml"}});
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("/nonexistent/robot.yaml: cannot open"),
            std::string::npos);
}

}  // namespace
}  // namespace selfcal::recording
