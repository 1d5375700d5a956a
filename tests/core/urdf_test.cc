// URDF import and export (protocols/model_file/urdf.h): import, convert to MCPC, export, import
// again; forward kinematics must agree with an independent composition of the URDF to 1e-9 m.
#include "protocols/model_file/urdf.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <random>

#include "core/model/kinematics.h"
#include "core/util/atomic_file.h"
#include "protocols/model_file/model_file.h"

namespace selfcal {
namespace {

constexpr double kTolerance = 1e-9;  // m and rotation-matrix entries: what the conversion promises

// What the test writes into a URDF joint, and composes by itself.
struct TestJoint {
  std::string name, type;  // revolute, continuous, prismatic, fixed
  Eigen::Vector3d xyz, rpy, axis;
};

Eigen::Matrix4d UrdfOrigin(const Eigen::Vector3d& xyz, const Eigen::Vector3d& rpy) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<3, 3>(0, 0) = (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) *
                         Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
                         Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
                            .toRotationMatrix();
  m.block<3, 1>(0, 3) = xyz;
  return m;
}

// Independent forward kinematics of the joints as written: product of origin * motion.
Eigen::Matrix4d Compose(const std::vector<TestJoint>& joints, const std::vector<double>& q) {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  std::size_t k = 0;
  for (const auto& j : joints) {
    T *= UrdfOrigin(j.xyz, j.rpy);
    if (j.type == "fixed") continue;
    Eigen::Matrix4d motion = Eigen::Matrix4d::Identity();
    if (j.type == "prismatic") {
      motion.block<3, 1>(0, 3) = q[k] * j.axis.normalized();
    } else {
      motion.block<3, 3>(0, 0) = Eigen::AngleAxisd(q[k], j.axis.normalized()).toRotationMatrix();
    }
    T *= motion;
    ++k;
  }
  return T;
}

std::string Vec(const Eigen::Vector3d& v) {
  char buffer[128];
  std::snprintf(buffer, sizeof(buffer), "%.17g %.17g %.17g", v.x(), v.y(), v.z());
  return buffer;
}

std::string ToUrdf(const std::vector<TestJoint>& joints) {
  std::string xml =
      "<?xml version=\"1.0\"?>\n<robot name=\"test_arm\">\n  <link name=\"world\"/>\n";
  for (std::size_t i = 0; i < joints.size(); ++i) {
    xml += "  <link name=\"l" + std::to_string(i) + "\"/>\n";
  }
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const TestJoint& j = joints[i];
    xml += "  <joint name=\"" + j.name + "\" type=\"" + j.type + "\">\n";
    xml += "    <parent link=\"" + (i == 0 ? std::string("world") : "l" + std::to_string(i - 1)) +
           "\"/>\n    <child link=\"l" + std::to_string(i) + "\"/>\n";
    xml += "    <origin xyz=\"" + Vec(j.xyz) + "\" rpy=\"" + Vec(j.rpy) + "\"/>\n";
    if (j.type != "fixed") xml += "    <axis xyz=\"" + Vec(j.axis) + "\"/>\n";
    if (j.type == "revolute") {
      xml += "    <limit lower=\"-2.5\" upper=\"2.5\" effort=\"10\" velocity=\"1.5\"/>\n";
    } else if (j.type == "prismatic") {
      xml += "    <limit lower=\"-0.2\" upper=\"0.3\" effort=\"10\" velocity=\"0.5\"/>\n";
    }
    xml += "  </joint>\n";
  }
  return xml + "</robot>\n";
}

// The KUKA LBR iiwa 14 joint origins of Drake's iiwa14_no_collision.urdf (the source named in
// config/robots/kuka_lbr_iiwa_r840.yaml), with the flange as a fixed joint.
std::vector<TestJoint> Iiwa() {
  const double pi = 3.141592653589793;
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  return {{"A1", "revolute", {0, 0, 0.1575}, {0, 0, 0}, z},
          {"A2", "revolute", {0, 0, 0.2025}, {pi / 2, 0, pi}, z},
          {"A3", "revolute", {0, 0.2045, 0}, {pi / 2, 0, pi}, z},
          {"A4", "revolute", {0, 0, 0.2155}, {pi / 2, 0, 0}, z},
          {"A5", "revolute", {0, 0.1845, 0}, {-pi / 2, pi, 0}, z},
          {"A6", "revolute", {0, 0, 0.2155}, {pi / 2, 0, 0}, z},
          {"A7", "revolute", {0, 0.081, 0}, {-pi / 2, pi, 0}, z},
          {"flange", "fixed", {0, 0, 0.045}, {0, 0, 0}, z}};
}

// A random arm: every joint type, fixed joints in between, tilted and non-unit axes.
std::vector<TestJoint> RandomArm(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  const char* types[] = {"fixed",    "revolute", "revolute", "prismatic", "continuous",
                         "revolute", "fixed",    "revolute", "revolute",  "fixed"};
  std::vector<TestJoint> joints;
  for (std::size_t i = 0; i < std::size(types); ++i) {
    TestJoint j;
    j.name = "j" + std::to_string(i);
    j.type = types[i];
    j.xyz = 0.3 * Eigen::Vector3d(u(rng), u(rng), u(rng));
    j.rpy = 3 * Eigen::Vector3d(u(rng), u(rng), u(rng));
    j.axis = 2 * Eigen::Vector3d(u(rng), u(rng), u(rng));
    joints.push_back(j);
  }
  joints[2].axis = {0, 0, -1};  // negative axis
  joints[5].rpy = {0, 0, 0};    // parallel to its predecessor's axis in its own frame
  joints[5].axis = joints[4].axis;
  return joints;
}

std::vector<std::vector<double>> Configurations(const RobotModel& model, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<std::vector<double>> result(300);
  for (auto& q : result) {
    for (const auto& joint : model.joints) {
      q.push_back(joint.lower + unit(rng) * (joint.upper - joint.lower));
    }
  }
  return result;
}

void ExpectSameAsUrdf(const std::vector<TestJoint>& joints, const RobotModel& model,
                      unsigned seed) {
  double worst_position = 0, worst_rotation = 0;
  for (const auto& q : Configurations(model, seed)) {
    const Eigen::Matrix4d expected = Compose(joints, q);
    const Eigen::Matrix4d actual = ForwardKinematics(model, q).matrix();
    worst_position =
        std::max(worst_position, (expected.block<3, 1>(0, 3) - actual.block<3, 1>(0, 3)).norm());
    worst_rotation =
        std::max(worst_rotation,
                 (expected.block<3, 3>(0, 0) - actual.block<3, 3>(0, 0)).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst_position, kTolerance);
  EXPECT_LT(worst_rotation, kTolerance);
}

TEST(Urdf, ImportExportImportKeepsTheKinematicsOfRandomArms) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const std::vector<TestJoint> arm = RandomArm(seed);
    const auto imported = ImportUrdf(ToUrdf(arm), "random.urdf", {});
    ASSERT_TRUE(imported.ok()) << imported.error().message;
    ASSERT_EQ(imported->model.JointCount(), 7u);
    EXPECT_EQ(imported->model.joints[2].type, JointType::kPrismatic);
    EXPECT_EQ(imported->model.joints[0].name, "j1");
    EXPECT_EQ(imported->model.joints[0].max_velocity, 1.5);
    EXPECT_EQ(imported->model.joints[2].lower, -0.2);
    ExpectSameAsUrdf(arm, imported->model, seed);

    const std::string exported = FormatUrdf(imported->model);
    const auto again = ImportUrdf(exported, "exported.urdf", {});
    ASSERT_TRUE(again.ok()) << again.error().message << "\n" << exported;
    ExpectSameAsUrdf(arm, again->model, seed + 10);
    EXPECT_EQ(again->model.joints[3].lower, -3.141592653589793);  // continuous, now revolute
  }
}

TEST(Urdf, DrakesIiwaMatchesTheCommittedModelFile) {
  const auto imported = ImportUrdf(ToUrdf(Iiwa()), "iiwa.urdf", {});
  ASSERT_TRUE(imported.ok()) << imported.error().message;
  ExpectSameAsUrdf(Iiwa(), imported->model, 3);
  const char* source = std::getenv("SELFCAL_SOURCE_DIR");
  ASSERT_NE(source, nullptr);
  const auto file = ReadModelFile(std::string(source) + "/config/robots/kuka_lbr_iiwa_r840.yaml");
  ASSERT_TRUE(file.ok()) << file.error().message;
  ExpectSameAsUrdf(Iiwa(), file->model, 4);
  // The canonical construction finds the committed parameters themselves.
  const auto k_imported = ToParameterVector(imported->model);
  const auto k_file = ToParameterVector(file->model);
  for (std::size_t i = 0; i < k_file.size(); ++i) {
    EXPECT_NEAR(k_imported[i], k_file[i], 1e-12) << ParameterName(file->model, i);
  }
}

TEST(Urdf, ExportOfAnMcpcModelImportsToTheSameParameters) {
  const char* source = std::getenv("SELFCAL_SOURCE_DIR");
  ASSERT_NE(source, nullptr);
  const auto file = ReadModelFile(std::string(source) + "/config/robots/kuka_lbr_iiwa_r840.yaml");
  ASSERT_TRUE(file.ok());
  RobotModel model = file->model;
  const auto again = ImportUrdf(FormatUrdf(model), "exported.urdf", {});
  ASSERT_TRUE(again.ok()) << again.error().message;
  const auto k = ToParameterVector(model);
  const auto k_again = ToParameterVector(again->model);
  for (std::size_t i = 0; i < k.size(); ++i) {
    EXPECT_NEAR(k_again[i], k[i], 1e-12) << ParameterName(model, i);
  }
  for (std::size_t i = 0; i < model.JointCount(); ++i) {
    EXPECT_EQ(again->model.joints[i].name, model.joints[i].name);
    EXPECT_EQ(again->model.joints[i].lower, model.joints[i].lower);
    EXPECT_EQ(again->model.joints[i].upper, model.joints[i].upper);
    EXPECT_EQ(again->model.joints[i].max_velocity, model.joints[i].max_velocity);
  }
}

TEST(Urdf, WritesAtomicallyAndReadsBack) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("selfcal_urdf_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const RobotModel model = ImportUrdf(ToUrdf(Iiwa()), "iiwa.urdf", {})->model;
  const std::string path = (dir / "iiwa.urdf").string();
  ASSERT_TRUE(WriteUrdfFile(path, model).ok());
  const auto read = ReadUrdfFile(path, {});
  ASSERT_TRUE(read.ok()) << read.error().message;
  ExpectSameAsUrdf(Iiwa(), read->model, 5);
  EXPECT_FALSE(WriteUrdfFile((dir / "missing" / "x.urdf").string(), model).ok());
  std::filesystem::remove_all(dir);
}

TEST(Urdf, BaseAndTipLinksCanBeChosen) {
  UrdfImportOptions options;
  options.base_link = "l1";  // after A2: five joints remain
  options.tip_link = "l6";   // A7's link, without the flange
  const auto imported = ImportUrdf(ToUrdf(Iiwa()), "iiwa.urdf", options);
  ASSERT_TRUE(imported.ok()) << imported.error().message;
  EXPECT_EQ(imported->model.JointCount(), 5u);
  EXPECT_EQ(imported->model.joints.front().name, "A3");
}

TEST(Urdf, BadDocumentsAreErrorsThatSayWhy) {
  auto message = [](const std::string& xml, UrdfImportOptions options = {}) {
    const auto result = ImportUrdf(xml, "bad.urdf", options);
    return result.ok() ? std::string("(no error)") : result.error().message;
  };
  EXPECT_NE(message("<robot").find("bad.urdf: not a valid URDF"), std::string::npos);
  EXPECT_NE(message("").find("not a valid URDF"), std::string::npos);

  std::string two_tips = ToUrdf(Iiwa());
  two_tips.insert(two_tips.find("</robot>"),
                  "<link name=\"camera\"/><joint name=\"cam\" type=\"fixed\"><parent link=\"l3\"/>"
                  "<child link=\"camera\"/></joint>\n");
  EXPECT_NE(message(two_tips).find("several tip links"), std::string::npos);
  UrdfImportOptions options;
  options.tip_link = "camera";
  EXPECT_EQ(message(two_tips, options), "(no error)");
  options.tip_link = "nope";
  EXPECT_NE(message(two_tips, options).find("no link named 'nope'"), std::string::npos);

  std::vector<TestJoint> floating = Iiwa();
  floating[3].type = "floating";
  EXPECT_NE(message(ToUrdf(floating)).find("joint 'A4'"), std::string::npos);

  std::vector<TestJoint> fixed_only = {Iiwa().back()};
  EXPECT_NE(message(ToUrdf(fixed_only)).find("no movable joint"), std::string::npos);

  std::string mimic = ToUrdf(Iiwa());
  mimic.replace(mimic.find("</joint>"), 8, "<mimic joint=\"A2\"/></joint>");
  EXPECT_NE(message(mimic).find("mimic"), std::string::npos);

  std::string reversed_limits = ToUrdf(Iiwa());
  reversed_limits.replace(reversed_limits.find("lower=\"-2.5\" upper=\"2.5\""), 25,
                          "lower=\"2.5\" upper=\"-2.5\"");
  EXPECT_NE(message(reversed_limits).find("lower limit"), std::string::npos);
}

}  // namespace
}  // namespace selfcal
