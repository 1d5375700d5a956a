#include "protocols/model_file/model_file.h"

#include <gtest/gtest.h>

#include "core/model/kinematics.h"
#include "core/util/atomic_file.h"
#include "protocols/model_file/sensor_config.h"

namespace selfcal {
namespace {

std::string SourceDir() {
  const char* dir = std::getenv("SELFCAL_SOURCE_DIR");
  return dir ? dir : ".";
}

const char* kTwoJoints = R"(name: two
joints:
  - {name: J1, type: revolute, lower: -1, upper: 1, max_velocity: 1, max_acceleration: 2}
  - {name: J2, type: prismatic, lower: 0, upper: 0.5, max_velocity: 0.1, max_acceleration: 0.2}
base: {alpha: 0, beta: 0, gamma: 0, x: 0, y: 0, z: 0.1}
segments:
  - {alpha: 0.1, beta: 0.2, x: 0.3, y: 0.4}
tool: {alpha: 0.5, beta: 0.6, gamma: 0.7, x: 0.8, y: 0.9, z: 1.0}
)";

// Replaces the first occurrence of `from` in kTwoJoints.
std::string Edited(const std::string& from, const std::string& to) {
  std::string text = kTwoJoints;
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

void ExpectError(const std::string& text, const std::vector<std::string>& fragments) {
  const auto file = ParseModelFile(text, "robot.yaml");
  ASSERT_FALSE(file.ok()) << "accepted:\n" << text;
  for (const auto& fragment : fragments) {
    EXPECT_NE(file.error().message.find(fragment), std::string::npos)
        << "'" << fragment << "' not in: " << file.error().message;
  }
}

TEST(ModelFile, ReadsTheDesignFormatWithTheDefaultMask) {
  const auto file = ParseModelFile(kTwoJoints, "robot.yaml");
  ASSERT_TRUE(file.ok()) << file.error().message;
  EXPECT_FALSE(file->mask_given);
  EXPECT_EQ(file->model.joints[1].type, JointType::kPrismatic);
  EXPECT_DOUBLE_EQ(file->model.segments[0].y, 0.4);
  EXPECT_DOUBLE_EQ(file->model.tool.gamma, 0.7);
  EXPECT_EQ(file->model.mask, DefaultMask(file->model));
}

TEST(ModelFile, RoundTripsExactlyWithMaskAndCalibrationSection) {
  auto file = ParseModelFile(kTwoJoints, "robot.yaml").value();
  RobotModel model = file.model;
  model.segments[0].x = 0.1 + 1e-15;  // needs all 17 digits
  model.tool.z = -1.0 / 3.0;
  model.mask = std::vector<bool>(model.ParameterCount(), false);
  model.mask[SegmentOffset(0) + 1] = true;
  model.mask[ToolOffset(2) + 5] = true;
  const std::string text = FormatModelFile(model, "iterations: 7\nreason: converged\n");
  const auto again = ParseModelFile(text, "again.yaml");
  ASSERT_TRUE(again.ok()) << again.error().message << "\n" << text;
  EXPECT_TRUE(again->mask_given);
  EXPECT_EQ(again->model.mask, model.mask);
  EXPECT_EQ(ToParameterVector(again->model), ToParameterVector(model));
  EXPECT_NE(again->calibration_yaml.find("iterations: 7"), std::string::npos);
  EXPECT_EQ(FormatModelFile(again->model, again->calibration_yaml), text);
}

// Names are free text: a joint "wrist, roll" inside the file's flow maps, or a robot "cell #2",
// once came back as other keys or a cut name; plain names stay plain.
TEST(ModelFile, NamesWithYamlPunctuationRoundTrip) {
  std::string text = Edited("name: two", "name: \"cell #2: 'a'\"");
  text.replace(text.find("name: J1"), 8, "name: \"wrist, roll\"");
  const auto file = ParseModelFile(text, "mem.yaml");
  ASSERT_TRUE(file.ok()) << file.error().message;
  const std::string formatted = FormatModelFile(file->model);
  const auto again = ParseModelFile(formatted, "again.yaml");
  ASSERT_TRUE(again.ok()) << again.error().message << "\n" << formatted;
  EXPECT_EQ(again->model.name, "cell #2: 'a'");
  EXPECT_EQ(again->model.joints[0].name, "wrist, roll");
  EXPECT_EQ(again->model.joints[1].name, "J2");
  EXPECT_NE(formatted.find("{name: J2,"), std::string::npos) << formatted;
}

TEST(ModelFile, UnknownKeyIsNamed) {
  ExpectError(Edited("name: two", "name: two\ncolour: red"), {"robot.yaml", "colour"});
  ExpectError(Edited("max_acceleration: 2}", "max_acceleration: 2, mass: 3}"),
              {"robot.yaml", "joints[0].mass"});
  ExpectError(Edited("z: 1.0}", "z: 1.0, w: 0}"), {"tool.w"});
}

TEST(ModelFile, MissingKeyIsNamed) {
  ExpectError(Edited("lower: 0, ", ""), {"robot.yaml", "joints[1].lower", "missing"});
  ExpectError(Edited("x: 0.3, ", ""), {"segments[0].x", "missing"});
  ExpectError(Edited("base: {alpha: 0, beta: 0, gamma: 0, x: 0, y: 0, z: 0.1}\n", ""),
              {"'base'", "missing"});
}

TEST(ModelFile, WrongTypeIsNamed) {
  ExpectError(Edited("upper: 1,", "upper: high,"), {"joints[0].upper", "wrong type"});
  ExpectError(Edited("type: prismatic", "type: spherical"), {"joints[1].type", "spherical"});
  ExpectError(Edited("segments:\n  - {", "segments:\n  - 3\n  - {"), {"segments"});
}

TEST(ModelFile, WrongJointCountIsNamed) {
  ExpectError(Edited("  - {alpha: 0.1, beta: 0.2, x: 0.3, y: 0.4}\n",
                     "  - {alpha: 0.1, beta: 0.2, x: 0.3, y: 0.4}\n"
                     "  - {alpha: 0.1, beta: 0.2, x: 0.3, y: 0.4}\n"),
              {"robot.yaml", "segments", "expected 1"});
  ExpectError(std::string(kTwoJoints) + "calibrate:\n  segments: [[alpha], [x]]\n  tool: [x]\n",
              {"calibrate.segments", "expected 1"});
  ExpectError(std::string(kTwoJoints) + "calibrate:\n  segments: [[alpha, delta]]\n  tool: [x]\n",
              {"calibrate.segments[0]", "delta"});
}

TEST(ModelFile, SyntaxErrorsAndMissingFilesSayWhere) {
  ExpectError("name: [unclosed", {"robot.yaml:", "syntax"});
  const auto missing = ReadModelFile("/nonexistent/robot.yaml");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find("/nonexistent/robot.yaml"), std::string::npos);
}

// A folder opens as a stream and throws from inside the stream buffer when read: every reader of
// our files says what it is instead.
TEST(ModelFile, AFolderIsNamedAsAFolder) {
  const std::string folder = SourceDir() + "/config";
  const std::string expected = folder + ": is a folder, not a file";
  const auto model = ReadModelFile(folder);
  ASSERT_FALSE(model.ok());
  EXPECT_EQ(model.error().message, expected);
  const auto sensor = ReadSensorConfig(folder);
  ASSERT_FALSE(sensor.ok());
  EXPECT_EQ(sensor.error().message, expected);
  const auto text = ReadFile(folder);
  ASSERT_FALSE(text.ok());
  EXPECT_EQ(text.error().message, expected);
}

TEST(ModelFile, GravityBlockRoundTripsAndBadMassesAreNamed) {
  const std::string text =
      std::string(kTwoJoints) +
      "gravity:\n  link_masses_kg: [2.5, 1.25]\n  sensor_mass_kg: 0.44\n"
      "  compliance_rad_per_nm: [5e-05, -2e-05]\n"  // a noisy estimate may be negative
      "  compliance_uncertainty_rad_per_nm: [5e-05, 1e-04]\n";
  const auto file = ParseModelFile(text, "robot.yaml");
  ASSERT_TRUE(file.ok()) << file.error().message;
  EXPECT_EQ(file->model.gravity.link_masses, (std::vector<double>{2.5, 1.25}));
  EXPECT_DOUBLE_EQ(file->model.gravity.sensor_mass, 0.44);
  EXPECT_EQ(file->model.compliance, (std::vector<double>{5e-05, -2e-05}));
  EXPECT_EQ(file->model.gravity.compliance_sd, (std::vector<double>{5e-05, 1e-04}));
  const auto again = ParseModelFile(FormatModelFile(file->model), "again.yaml");
  ASSERT_TRUE(again.ok()) << again.error().message;
  EXPECT_EQ(again->model.gravity.link_masses, file->model.gravity.link_masses);
  EXPECT_EQ(again->model.gravity.sensor_mass, file->model.gravity.sensor_mass);
  EXPECT_EQ(again->model.compliance, file->model.compliance);
  EXPECT_EQ(again->model.gravity.compliance_sd, file->model.gravity.compliance_sd);
  EXPECT_FALSE(ParseModelFile(kTwoJoints, "robot.yaml")->model.gravity.Present());  // optional
  const std::string block = std::string(kTwoJoints) + "gravity:\n";
  ExpectError(block + "  link_masses_kg: [2.5]\n", {"gravity.link_masses_kg", "one per joint"});
  ExpectError(block + "  link_masses_kg: [2.5, 0]\n", {"gravity.link_masses_kg", "> 0"});
  ExpectError(block + "  sensor_mass_kg: 1\n", {"gravity.link_masses_kg", "missing"});
  ExpectError(block + "  link_masses_kg: [1, 1]\n  sensor_mass_kg: -1\n",
              {"gravity.sensor_mass_kg"});
  ExpectError(block + "  link_masses_kg: [1, 1]\n  stiffness: [1, 1]\n", {"gravity.stiffness"});
  ExpectError(block + "  link_masses_kg: [1, 1]\n  compliance_rad_per_nm: [1, .nan]\n",
              {"gravity.compliance_rad_per_nm", "finite"});
  ExpectError(block + "  link_masses_kg: [1, 1]\n  compliance_uncertainty_rad_per_nm: [1e-4, -1]\n",
              {"gravity.compliance_uncertainty_rad_per_nm", ">= 0"});
}

TEST(ModelFile, LinksBlockRoundTripsAndABadRadiusIsNamed) {
  const auto file = ParseModelFile(std::string(kTwoJoints) + "links: {radius_m: 0.07}\n", "r.yaml");
  ASSERT_TRUE(file.ok()) << file.error().message;
  EXPECT_DOUBLE_EQ(file->model.link_radius, 0.07);
  const auto again = ParseModelFile(FormatModelFile(file->model), "again.yaml");
  ASSERT_TRUE(again.ok()) << again.error().message;
  EXPECT_EQ(again->model.link_radius, 0.07);
  EXPECT_EQ(ParseModelFile(kTwoJoints, "robot.yaml")->model.link_radius, 0.0);  // optional
  const std::string block = std::string(kTwoJoints) + "links: ";
  ExpectError(block + "{radius_m: 0}\n", {"links.radius_m", "(0, 0.5] m"});
  ExpectError(block + "{radius_m: 0.9}\n", {"links.radius_m", "(0, 0.5] m"});
  ExpectError(block + "{}\n", {"links.radius_m", "missing"});
  ExpectError(block + "{radius_m: 0.1, mesh: arm.stl}\n", {"links.mesh"});
}

TEST(ModelFile, ShippedIiwaModelHasThePapers28Parameters) {
  const auto file = ReadModelFile(SourceDir() + "/config/robots/kuka_lbr_iiwa_r840.yaml");
  ASSERT_TRUE(file.ok()) << file.error().message;
  std::size_t calibrated = 0;
  for (bool flag : file->model.mask) calibrated += flag;
  EXPECT_EQ(file->model.JointCount(), 7u);
  EXPECT_EQ(calibrated, 28u);
  EXPECT_EQ(file->model.gravity.link_masses.size(), 7u);  // Drake's link masses
  // Zero configuration: the arm stands straight up; flange at 0.36 + 0.42 + 0.40 + 0.126 m.
  const auto T_base_flange = ForwardKinematics(file->model, std::vector<double>(7, 0.0));
  EXPECT_NEAR(T_base_flange.translation().z(), 1.306, 1e-12);
  EXPECT_NEAR(T_base_flange.translation().head<2>().norm(), 0.0, 1e-12);
}

}  // namespace
}  // namespace selfcal
