// config/robots/ur5.yaml against UR's DH table: same forward kinematics, and the DH import
// (config/robots/sources/ur5_dh.yaml through ChainToMcpc) reproduces the committed parameters.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "core/model/chain.h"
#include "core/model/kinematics.h"
#include "protocols/model_file/dh_file.h"
#include "protocols/model_file/model_file.h"

namespace selfcal {
namespace {

std::string SourceDir() {
  const char* dir = std::getenv("SELFCAL_SOURCE_DIR");
  return dir != nullptr ? dir : ".";
}

// UR5 (CB3, "serie 3") standard DH, written out independently of the YAML files.
constexpr double kD[6] = {0.089159, 0, 0, 0.10915, 0.09465, 0.0823};
constexpr double kA[6] = {0, -0.425, -0.39225, 0, 0, 0};
constexpr double kAlpha[6] = {std::numbers::pi / 2,  0, 0, std::numbers::pi / 2,
                              -std::numbers::pi / 2, 0};

Eigen::Matrix4d Dh(double theta, double d, double a, double alpha) {
  const double ct = std::cos(theta), st = std::sin(theta);
  const double ca = std::cos(alpha), sa = std::sin(alpha);
  Eigen::Matrix4d m;
  m << ct, -st * ca, st * sa, a * ct, st, ct * ca, -ct * sa, a * st, 0, sa, ca, d, 0, 0, 0, 1;
  return m;
}

Eigen::Matrix4d UrForwardKinematics(const std::vector<double>& q) {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  for (int i = 0; i < 6; ++i) T *= Dh(q[static_cast<std::size_t>(i)], kD[i], kA[i], kAlpha[i]);
  return T;
}

TEST(Ur5, ModelFileMatchesTheDhTable) {
  const auto file = ReadModelFile(SourceDir() + "/config/robots/ur5.yaml");
  ASSERT_TRUE(file.ok()) << file.error().message;
  const RobotModel& model = file->model;
  ASSERT_EQ(model.JointCount(), 6u);
  std::size_t calibrated = 0;
  for (bool flag : model.mask) calibrated += flag ? 1 : 0;
  EXPECT_EQ(calibrated, 24u);

  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-2 * std::numbers::pi, 2 * std::numbers::pi);
  double worst = 0;
  for (int trial = 0; trial < 500; ++trial) {
    std::vector<double> q(6);
    for (auto& v : q) v = u(rng);
    const Eigen::Matrix4d expected = UrForwardKinematics(q);
    const Eigen::Matrix4d actual = ForwardKinematics(model, q).matrix();
    worst = std::max(worst, (expected - actual).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst, 1e-12);
  // Zero configuration: the arm lies stretched along -x, wrist offsets along y and z.
  const Eigen::Matrix4d zero = UrForwardKinematics(std::vector<double>(6, 0.0));
  EXPECT_NEAR(zero(0, 3), -0.81725, 1e-12);
  EXPECT_NEAR(zero(1, 3), -0.10915 - 0.0823, 1e-12);
  EXPECT_NEAR(zero(2, 3), 0.089159 - 0.09465, 1e-12);
}

TEST(Ur5, DhImportReproducesTheCommittedParameters) {
  const auto table = ReadDhFile(SourceDir() + "/config/robots/sources/ur5_dh.yaml");
  ASSERT_TRUE(table.ok()) << table.error().message;
  const auto converted = ChainToMcpc(DhToChain(*table));
  ASSERT_TRUE(converted.ok()) << converted.error().message;
  const auto file = ReadModelFile(SourceDir() + "/config/robots/ur5.yaml");
  ASSERT_TRUE(file.ok());
  const auto k_imported = ToParameterVector(converted->model);
  const auto k_file = ToParameterVector(file->model);
  ASSERT_EQ(k_imported.size(), k_file.size());
  for (std::size_t i = 0; i < k_file.size(); ++i) {
    EXPECT_NEAR(k_imported[i], k_file[i], 1e-12) << ParameterName(file->model, i);
  }
  for (std::size_t i = 0; i < 6; ++i) {
    EXPECT_EQ(converted->model.joints[i].name, file->model.joints[i].name);
    EXPECT_EQ(converted->model.joints[i].upper, file->model.joints[i].upper);
  }
}

TEST(DhFile, BadTablesSayWhere) {
  const auto missing_key =
      ParseDhFile("name: x\njoints:\n  - {name: a, type: revolute}\n", "t.yaml");
  ASSERT_FALSE(missing_key.ok());
  EXPECT_NE(missing_key.error().message.find("t.yaml"), std::string::npos);
  EXPECT_NE(missing_key.error().message.find("joints[0]"), std::string::npos);
  const auto unknown = ParseDhFile(
      "name: x\nextra: 1\njoints:\n  - {name: a, type: revolute, d: 0, theta: 0, a: 0, alpha: 0, "
      "lower: -1, upper: 1, max_velocity: 1, max_acceleration: 1}\n",
      "t.yaml");
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.error().message.find("extra"), std::string::npos);
  const auto bad_origin = ParseDhFile(
      "name: x\nbase: {xyz: [0, 0], rpy: [0, 0, 0]}\njoints:\n  - {name: a, type: prismatic, d: 0, "
      "theta: 0, a: 0, alpha: 0, lower: -1, upper: 1, max_velocity: 1, max_acceleration: 1}\n",
      "t.yaml");
  ASSERT_FALSE(bad_origin.ok());
  EXPECT_NE(bad_origin.error().message.find("base.xyz"), std::string::npos)
      << bad_origin.error().message;
  const auto good = ParseDhFile(
      "name: x\ntool: {xyz: [0, 0, 0.1], rpy: [0, 0, 1]}\njoints:\n  - {name: a, type: prismatic, "
      "d: 0, theta: 0, a: 0, alpha: 0, lower: -1, upper: 1, max_velocity: 1, max_acceleration: "
      "1}\n",
      "t.yaml");
  ASSERT_TRUE(good.ok()) << good.error().message;
  EXPECT_EQ(good->rows[0].joint.type, JointType::kPrismatic);
  EXPECT_NEAR(good->T_framen_tool.translation().z(), 0.1, 1e-15);
}

}  // namespace
}  // namespace selfcal
