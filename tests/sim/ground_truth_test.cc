// Ground truth: the nominal model is 20-40 mm (RMS, sensor position) off the truth, only
// calibrated parameters differ, and the perturbation is a function of the seed.
#include "core/sim/ground_truth.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <numbers>
#include <string>

#include "core/model/evaluation.h"
#include "core/model/kinematics.h"
#include "core/sim/ik.h"
#include "core/sim/mount.h"
#include "core/sim/random.h"
#include "protocols/model_file/model_file.h"

namespace selfcal::sim {
namespace {

RobotModel Iiwa() {
  const char* root = std::getenv("SELFCAL_SOURCE_DIR");
  auto file =
      ReadModelFile(std::string(root ? root : ".") + "/config/robots/kuka_lbr_iiwa_r840.yaml");
  EXPECT_TRUE(file.ok());
  return WithSensorMount(file->model, {0.01, -0.045, 0.075, 0.1, -0.2, 0.3});
}

TEST(GroundTruth, NominalIsTwentyToFortyMillimetresOff) {
  const RobotModel nominal = Iiwa();
  for (std::uint64_t seed : {1u, 2u, 3u, 11u, 12345u}) {
    const RobotModel truth = PerturbModel(nominal, seed);
    // Measured on configurations the perturbation never saw.
    const PoseErrorStats error = SensorPoseError(truth, nominal, 1000, seed + 1000);
    EXPECT_GE(error.rms_position_m, 0.020) << "seed " << seed;
    EXPECT_LE(error.rms_position_m, 0.040) << "seed " << seed;
    EXPECT_NEAR(error.rms_position_m, 0.030, 0.004) << "seed " << seed;
    // Orientation error of the same order as the paper's URDF (2.06 deg).
    EXPECT_GT(error.rms_orientation_rad, 0.3 * std::numbers::pi / 180);
    EXPECT_LT(error.rms_orientation_rad, 4.0 * std::numbers::pi / 180);
    const auto k_truth = ToParameterVector(truth);
    const auto k_nominal = ToParameterVector(nominal);
    int changed = 0;
    for (std::size_t i = 0; i < k_truth.size(); ++i) {
      if (!nominal.mask[i]) {
        EXPECT_EQ(k_truth[i], k_nominal[i]) << ParameterName(nominal, i);
      } else if (k_truth[i] != k_nominal[i]) {
        ++changed;
      }
    }
    EXPECT_EQ(changed, 28);  // every calibrated parameter of the paper's mask
  }
  // Same seed, same truth; another seed, another truth.
  EXPECT_EQ(ToParameterVector(PerturbModel(nominal, 5)),
            ToParameterVector(PerturbModel(nominal, 5)));
  EXPECT_NE(ToParameterVector(PerturbModel(nominal, 5)),
            ToParameterVector(PerturbModel(nominal, 6)));
}

TEST(GroundTruth, SensorMountComposesWithTheFlange) {
  const char* root = std::getenv("SELFCAL_SOURCE_DIR");
  auto file =
      ReadModelFile(std::string(root ? root : ".") + "/config/robots/kuka_lbr_iiwa_r840.yaml");
  ASSERT_TRUE(file.ok());
  const SensorMount mount{0.02, -0.045, 0.075, 0.4, -1.2, 2.5};
  const RobotModel mounted = WithSensorMount(file->model, mount);
  Random random(9);
  for (int k = 0; k < 50; ++k) {
    const auto q = RandomConfiguration(file->model, 0, random);
    const Eigen::Isometry3d expected = ForwardKinematics(file->model, q) * mount.Transform();
    const Eigen::Isometry3d actual = ForwardKinematics(mounted, q);
    EXPECT_LT((expected.matrix() - actual.matrix()).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(GroundTruth, InverseKinematicsReachesPoses) {
  const RobotModel model = Iiwa();
  Random random(4);
  int solved = 0;
  for (int k = 0; k < 10; ++k) {
    const auto q = RandomConfiguration(model, 0.2, random);
    const Eigen::Isometry3d goal = ForwardKinematics(model, q);
    const auto solution = SolveIk(model, goal, {}, random);
    if (!solution) continue;
    ++solved;
    const Eigen::Isometry3d reached = ForwardKinematics(model, *solution);
    EXPECT_LT((reached.translation() - goal.translation()).norm(), 1e-4);
    EXPECT_LT(Eigen::AngleAxisd(reached.linear().transpose() * goal.linear()).angle(), 1e-3);
  }
  EXPECT_GE(solved, 9);
}

}  // namespace
}  // namespace selfcal::sim
