// The convergence measure of deviation 18 (core/calib/sensor_motion.h) on the iiwa: a direction
// of the parameters that moves no sensor pose measures nothing, a translation of the mount
// measures its own size, and the step is the metric's quadratic form.
#include "core/calib/sensor_motion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <numbers>
#include <random>

#include "core/model/kinematics.h"
#include "core/model/normalization.h"
#include "protocols/model_file/model_file.h"

namespace selfcal::calib {
namespace {

constexpr double kScale = 1.2;  // s [m]

std::string SourceDir() {  // ctest sets SELFCAL_SOURCE_DIR
  const char* source = std::getenv("SELFCAL_SOURCE_DIR");
  return source != nullptr ? source : ".";
}

class SensorMotionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto robot = ReadModelFile(SourceDir() + "/config/robots/kuka_lbr_iiwa_r840.yaml");
    ASSERT_TRUE(robot.ok()) << robot.error().message;
    model_ = robot->model;
    // A sensor looking sideways, as the demo's Hokuyo: the tool's beta at -90 deg.
    model_.tool.beta = -std::numbers::pi / 2;
    model_.tool.z = 0.09;
    chain_ = Chain{JointTypes(model_), kScale, false, {}, {}};
    K_ = chain_.ParameterCount();
    for (std::size_t i = 0; i < K_; ++i) free_.push_back(i);
    std::mt19937 random(7);
    for (int scan = 0; scan < 6; ++scan) {
      Dataset dataset;
      dataset.joint_count = model_.JointCount();
      for (const JointSpec& joint : model_.joints) {
        std::uniform_real_distribution<double> q(0.8 * joint.lower, 0.8 * joint.upper);
        dataset.pose_joints.push_back(q(random));
      }
      datasets_.push_back(std::move(dataset));
    }
    k_hat_ = ToParameterVector(model_);
    NormalizeTranslationParameters(k_hat_, model_.JointCount(), kScale);
  }

  std::size_t Tool(std::size_t offset) const { return K_ - 6 + offset; }  // alpha .. z

  RobotModel model_;
  Chain chain_;
  std::size_t K_ = 0;
  std::vector<std::size_t> free_;
  std::vector<Dataset> datasets_;
  std::vector<double> k_hat_;
};

TEST_F(SensorMotionTest, TheToolsAlphaPlusGammaAtBetaMinus90MovesNothing) {
  const SensorMotion motion(chain_, free_, datasets_);
  std::vector<double> after = k_hat_;
  after[Tool(0)] += 0.01;  // alpha
  after[Tool(2)] += 0.01;  // gamma: rot_x(a) rot_y(-90 deg) rot_z(g) = rot_x(a - g) rot_y(-90 deg)
  EXPECT_LT(motion.Step(k_hat_, after), 1e-10);  // |delta k_hat| is 0.014
  after[Tool(2)] -= 0.02;                        // alpha - gamma turns the sensor
  EXPECT_GT(motion.Step(k_hat_, after), 0.01);
}

TEST_F(SensorMotionTest, AShiftOfTheMountMeasuresItsOwnSize) {
  const SensorMotion motion(chain_, free_, datasets_);
  std::vector<double> after = k_hat_;
  after[Tool(3)] += 2e-4;  // x / s: the sensor moves 2e-4 s, nothing turns
  EXPECT_NEAR(motion.Step(k_hat_, after), 2e-4, 1e-12);
}

TEST_F(SensorMotionTest, OnlyTheFreeParametersCount) {
  const std::vector<std::size_t> mount_only = {Tool(3), Tool(4), Tool(5)};
  const SensorMotion motion(chain_, mount_only, datasets_);
  std::vector<double> after = k_hat_;
  after[Tool(0)] += 0.1;  // not free
  EXPECT_EQ(motion.Step(k_hat_, after), 0.0);
  after[Tool(5)] += 1e-3;
  EXPECT_NEAR(motion.Step(k_hat_, after), 1e-3, 1e-12);
}

TEST_F(SensorMotionTest, TheStepIsTheMetricsQuadraticForm) {
  const SensorMotion motion(chain_, free_, datasets_);
  std::mt19937 random(3);
  std::normal_distribution<double> normal(0.0, 1e-3);
  Eigen::VectorXd d(static_cast<Eigen::Index>(K_));
  std::vector<double> after = k_hat_;
  for (std::size_t i = 0; i < K_; ++i) {
    d[static_cast<Eigen::Index>(i)] = normal(random);
    after[i] += d[static_cast<Eigen::Index>(i)];
  }
  const Eigen::MatrixXd M = motion.Metric(k_hat_);
  EXPECT_NEAR(motion.Step(k_hat_, after), std::sqrt(d.dot(M * d)), 1e-12);
  EXPECT_LT((M - M.transpose()).norm(), 1e-12 * M.norm());
}

TEST_F(SensorMotionTest, WithoutAnyFitPoseItIsTheParametersStep) {
  for (Dataset& dataset : datasets_) dataset.validation = true;
  const SensorMotion motion(chain_, free_, datasets_);
  std::vector<double> after = k_hat_;
  after[Tool(0)] += 3e-3;
  after[Tool(2)] += 4e-3;
  EXPECT_NEAR(motion.Step(k_hat_, after), 5e-3, 1e-12);
}

}  // namespace
}  // namespace selfcal::calib
