// The predicted error map over the joint space (core/calib/predicted_error.h, covariance.h):
// its bins agree with PredictPoseError on the same configurations, and its worst region is
// where the geometry says an uncertain parameter moves the sensor most.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/calib/covariance.h"
#include "core/model/evaluation.h"
#include "tests/calib/synthetic.h"

namespace selfcal::calib {
namespace {

// A random covariance over the free parameters (SPD), 1 mm and 1 mrad order.
Eigen::MatrixXd RandomCovariance(long k, unsigned seed) {
  std::mt19937 random(seed);
  std::normal_distribution<double> normal(0.0, 1e-3);
  Eigen::MatrixXd a(k, k);
  for (long r = 0; r < k; ++r)
    for (long c = 0; c < k; ++c) a(r, c) = normal(random);
  return a * a.transpose() / static_cast<double>(k);
}

std::vector<std::size_t> FreeOf(const RobotModel& model) {
  std::vector<std::size_t> free;
  for (std::size_t i = 0; i < model.mask.size(); ++i)
    if (model.mask[i]) free.push_back(i);
  return free;
}

// Every bin of every joint: the configurations of the sample whose joint lies in it, predicted
// on their own, give the bin's samples and RMS.
TEST(PredictedErrorMap, BinsAgreeWithThePredictionOnTheirConfigurations) {
  const RobotModel model = testing::LoadIiwa();
  const std::vector<std::size_t> free = FreeOf(model);
  const Eigen::MatrixXd covariance = RandomCovariance(static_cast<long>(free.size()), 5);
  const PredictedError predicted =
      PredictPoseError(model, free, covariance, kPredictionSamples, kPredictionSeed);
  const auto configurations = RandomConfigurations(model, kPredictionSamples, kPredictionSeed);
  ASSERT_EQ(predicted.map.joints.size(), model.JointCount());
  for (std::size_t j = 0; j < model.JointCount(); ++j) {
    const JointErrorProfile& profile = predicted.map.joints[j];
    EXPECT_EQ(profile.joint, model.joints[j].name);
    ASSERT_EQ(profile.samples.size(), kErrorMapBins);
    const double width = (profile.upper - profile.lower) / static_cast<double>(kErrorMapBins);
    std::size_t total = 0;
    for (std::size_t bin = 0; bin < kErrorMapBins; ++bin) {
      const double lower = profile.lower + width * static_cast<double>(bin), upper = lower + width;
      std::vector<std::vector<double>> inside;
      for (const auto& q : configurations)
        if (q[j] >= lower && (q[j] < upper || bin + 1 == kErrorMapBins)) inside.push_back(q);
      const PredictedError own = PredictPoseError(model, free, covariance, inside);
      EXPECT_EQ(profile.samples[bin], inside.size()) << profile.joint << " bin " << bin;
      ASSERT_GT(inside.size(), 40u) << "500 uniform samples fill every sixth of a range";
      EXPECT_NEAR(profile.sensor_rms_position_m[bin], own.sensor.rms_position_m, 1e-15);
      EXPECT_NEAR(profile.flange_rms_position_m[bin], own.flange.rms_position_m, 1e-15);
      total += inside.size();
    }
    EXPECT_EQ(total, kPredictionSamples);
  }
  ASSERT_EQ(predicted.map.worst.size(), kWorstRegions);
  for (std::size_t r = 1; r < predicted.map.worst.size(); ++r)
    EXPECT_GE(predicted.map.worst[r - 1].sensor_rms_position_m,
              predicted.map.worst[r].sensor_rms_position_m);
  // The worst bin's mean variance is at least the mean over all bins.
  EXPECT_GE(predicted.map.worst[0].sensor_rms_position_m, predicted.sensor.rms_position_m);
  EXPECT_LE(predicted.map.worst[0].sensor_rms_position_m, predicted.sensor.max_position_m);
}

// Two revolute joints about parallel z axes, links of 1 m along x: the sensor sits at
// Rz(q1) ((1, 0, 0) + Rz(q2) (1, 0, 0)). A tilt of the first segment about its x axis moves it
// by |sin q2| per radian, about its y axis by 1 + cos q2.
RobotModel PlanarArm() {
  RobotModel model;
  model.name = "planar";
  model.joints = {{"A1", JointType::kRevolute, -M_PI, M_PI, 1, 1},
                  {"A2", JointType::kRevolute, -M_PI, M_PI, 1, 1}};
  model.segments = {{0, 0, 1.0, 0}};
  model.tool.x = 1.0;
  model.mask = DefaultMask(model);
  return model;
}

// The worst region of the map with one uncertain parameter of the first segment (1 mrad;
// everything else 1 urad or 1 um).
ErrorRegion WorstWithUncertain(const std::string& name) {
  const RobotModel model = PlanarArm();
  const std::vector<std::size_t> free = {SegmentOffset(0), SegmentOffset(0) + 1, ToolOffset(2) + 3};
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Identity(3, 3) * 1e-12;
  for (long c = 0; c < 3; ++c)
    if (ParameterName(model, free[static_cast<std::size_t>(c)]) == name) covariance(c, c) = 1e-6;
  EXPECT_EQ(covariance.maxCoeff(), 1e-6) << name;
  const PredictedError predicted =
      PredictPoseError(model, free, covariance, kPredictionSamples, kPredictionSeed);
  EXPECT_EQ(predicted.map.worst.size(), 2u);
  return predicted.map.worst.at(0);
}

TEST(PredictedErrorMap, AnUncertainTiltMakesItsJointRangeTheWorst) {
  // About x: largest at q2 = +-90 deg, the bins [-120, -60] and [60, 120] deg.
  const ErrorRegion x = WorstWithUncertain("A1->A2.alpha");
  EXPECT_EQ(x.joint, 1u) << "A2's angle decides it; A1 turns the whole arm";
  EXPECT_TRUE(x.bin == 1 || x.bin == 4) << x.bin;
  EXPECT_NEAR(std::abs(x.lower + x.upper) / 2, M_PI / 2, 1e-12);
  // RMS of |sin| over [60, 120] deg: sqrt(1/2 + 3 sqrt(3) / (4 pi)) = 0.956 mm, within sampling.
  EXPECT_NEAR(x.sensor_rms_position_m, 0.956e-3, 0.03e-3);
  // About y: largest with the arm stretched, q2 = 0, the bins [-60, 0] and [0, 60] deg.
  const ErrorRegion y = WorstWithUncertain("A1->A2.beta");
  EXPECT_EQ(y.joint, 1u);
  EXPECT_TRUE(y.bin == 2 || y.bin == 3) << y.bin;
  EXPECT_GT(y.sensor_rms_position_m, 1.7e-3);  // 1 + cos q2 is 1.5 to 2 there
}

}  // namespace
}  // namespace selfcal::calib
