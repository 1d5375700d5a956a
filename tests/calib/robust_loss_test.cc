// The robust loss (core/calib/robust_loss.h, docs/engine.md deviation 14): Cauchy's weights, the
// kernel's scale from the sensor's noise at each point's range, and that a weighted rigid pair's
// reduction is exactly sum w r^2 at any poses.
#include "core/calib/robust_loss.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/calib/rigid_pair.h"

namespace selfcal::calib {
namespace {

TEST(RobustLoss, CauchyWeights) {
  EXPECT_DOUBLE_EQ(CauchyWeight(0.0, 2.0), 1.0);
  EXPECT_DOUBLE_EQ(CauchyWeight(2.0, 2.0), 0.5);
  EXPECT_DOUBLE_EQ(CauchyWeight(-4.0, 2.0), 0.2);
}

// Scan i: three points along the sensor's z at ranges 1, 2 and 3 m, on the plane z = 0 of the
// base frame (normal +z); scan j: the same points moved by `offsets` along the normal.
struct TwoScans {
  Dataset dataset_i, dataset_j;
  ProjectedCloud cloud_i, cloud_j;
  PairMatches matches;
};
TwoScans MakeScans(const std::vector<float>& offsets) {
  TwoScans scans;
  for (Dataset* dataset : {&scans.dataset_i, &scans.dataset_j}) {
    dataset->rows = 1;
    dataset->cols = offsets.size();
    dataset->joint_count = 0;
    for (std::size_t k = 0; k < offsets.size(); ++k) {
      dataset->x.push_back(0.f);
      dataset->y.push_back(0.f);
      dataset->z.push_back(static_cast<float>(k + 1));  // m: range k + 1
    }
  }
  for (ProjectedCloud* cloud : {&scans.cloud_i, &scans.cloud_j}) {
    cloud->rows = 1;
    cloud->cols = offsets.size();
    for (std::size_t k = 0; k < offsets.size(); ++k) {
      cloud->x.push_back(static_cast<float>(k));
      cloud->y.push_back(0.f);
      cloud->z.push_back(cloud == &scans.cloud_j ? offsets[k] : 0.f);
      cloud->nx.push_back(0.f);
      cloud->ny.push_back(0.f);
      cloud->nz.push_back(1.f);
      cloud->keep.push_back(1);
    }
  }
  scans.matches.dataset_j = 1;
  for (std::uint32_t k = 0; k < offsets.size(); ++k) {
    scans.matches.point_i.push_back(k);
    scans.matches.point_j.push_back(k);
  }
  return scans;
}

TEST(RobustLoss, KernelScaleIsTheMatchNoiseAtEachRange) {
  const TwoScans scans = MakeScans({0.01f, -0.02f, 0.03f});
  CalibrationOptions options;
  options.loss = LossKind::kCauchy;
  options.loss_width = 2.0;
  options.sigma_abs = 0.002;  // m
  options.sigma_rel = 0.001;  // of the range
  const double scale = 0.5;   // normalized units: m / 0.5; residuals above are normalized
  const RobustLoss loss = MakeRobustLoss(options, scale);
  ASSERT_TRUE(loss.Active());
  const std::vector<float> weights =
      MatchWeights(loss, CostKind::kPaper, scans.matches, scans.cloud_i, scans.cloud_j,
                   scans.dataset_i, scans.dataset_j, scale);
  ASSERT_EQ(weights.size(), 3u);
  const double offsets[3] = {0.01, -0.02, 0.03};
  for (int k = 0; k < 3; ++k) {
    const double sigma = (0.002 + 0.001 * (k + 1)) / scale;  // both points at range k + 1
    const double kernel = 2.0 * std::sqrt(2.0) * sigma;
    const double u = offsets[k] / kernel;
    EXPECT_NEAR(weights[static_cast<std::size_t>(k)], 1.0 / (1.0 + u * u), 1e-6) << k;
  }
  EXPECT_LT(weights[1], weights[0]);  // farther off the plane at about the same noise
}

TEST(RobustLoss, SquaredLossAndNoiseFreeSensorsWeighNothing) {
  const TwoScans scans = MakeScans({0.01f});
  CalibrationOptions options;
  options.sigma_abs = 0.002;
  options.loss = LossKind::kSquared;
  EXPECT_FALSE(MakeRobustLoss(options, 1.0).Active());
  EXPECT_TRUE(MatchWeights(MakeRobustLoss(options, 1.0), CostKind::kPaper, scans.matches,
                           scans.cloud_i, scans.cloud_j, scans.dataset_i, scans.dataset_j, 1.0)
                  .empty());
  options.loss = LossKind::kCauchy;
  options.sigma_abs = 0;
  options.sigma_rel = 0;
  EXPECT_FALSE(MakeRobustLoss(options, 1.0).Active());  // no scale: the squared loss
  EXPECT_EQ(SumOfWeights({}, 7), 7.0);
  EXPECT_DOUBLE_EQ(SumOfWeights({0.25f, 0.5f}, 2), 0.75);
}

TEST(RobustLoss, WeightedRigidPairIsExactlyTheWeightedSum) {
  const TwoScans scans = MakeScans({0.01f, -0.02f, 0.03f});
  const std::vector<float> weights = {1.0f, 0.25f, 0.5f};
  Eigen::Matrix<double, 3, 4> T_i = Eigen::Matrix<double, 3, 4>::Zero(), T_j = T_i;
  T_i.leftCols<3>().setIdentity();
  T_j.leftCols<3>().setIdentity();
  T_j(2, 3) = 0.004;
  const RigidPairCost pair =
      ReduceRigidPair(scans.matches, CostKind::kPaper, scans.cloud_i, scans.cloud_j,
                      scans.dataset_i, scans.dataset_j, 1.0, T_i, T_j, weights);
  // Moved poses: a small rotation about x and a shift of scan i.
  Eigen::Matrix<double, 3, 4> U_i = T_i, U_j = T_j;
  const double angle = 0.01;
  U_i.block<2, 2>(1, 1) << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
  U_i.col(3) << 0.001, -0.002, 0.003;
  double expected = 0;
  for (std::size_t k = 0; k < 3; ++k) {
    const Eigen::Vector3d p(0, 0, static_cast<double>(k + 1));
    const double r = Eigen::Vector3d::UnitZ().dot((U_i.leftCols<3>() * p + U_i.col(3)) -
                                                  (U_j.leftCols<3>() * p + U_j.col(3)));
    expected += weights[k] * r * r;
  }
  const double reduced = RigidPairSquaredSum(pair, Eigen::Map<const PoseEntries>(U_i.data()),
                                             Eigen::Map<const PoseEntries>(U_j.data()),
                                             Eigen::VectorXd(), nullptr, nullptr, nullptr, nullptr);
  EXPECT_NEAR(reduced, expected, 1e-15 + 1e-12 * expected);
  EXPECT_GT(expected, 0);
}

TEST(RobustLoss, OptionsNameABadWidth) {
  CalibrationOptions options;
  std::string error;
  EXPECT_TRUE(options.IsValid(&error)) << error;
  options.loss_width = 0;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("loss_width = 0"), std::string::npos) << error;
  options.loss_width = 2.3849;
  options.loss = static_cast<LossKind>(7);
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("loss"), std::string::npos) << error;
}

}  // namespace
}  // namespace selfcal::calib
