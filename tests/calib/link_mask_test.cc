// The arm's own links removed before matching (docs/engine.md, deviation 20; link_mask.h): points
// sampled on the surface of the iiwa's link capsules (radius 7 cm) and points of the scene 15 cm
// or more beyond any link, seen from the sensor at the arm's tip. The mask must remove exactly
// the former, at the model the points were made with, at a model a centimetre off (the margin),
// and in a LiDAR sweep where every point has its own pose (the capsules follow the arm).
#include "core/calib/link_mask.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <string>

#include "core/calib/chain.h"
#include "core/model/arm_capsules.h"
#include "core/model/normalization.h"
#include "protocols/model_file/model_file.h"

namespace selfcal::calib {
namespace {

constexpr double kLinkRadius = 0.07;  // m
constexpr double kMargin = 0.03;      // m, CalibrationOptions' default
constexpr double kScale = 0.8;        // m: the normalization scale s

struct Sample {
  Eigen::Vector3d base_point;  // m
  bool on_link = false;
};

RobotModel Iiwa() {
  const char* source = std::getenv("SELFCAL_SOURCE_DIR");  // set by ctest
  auto robot = ReadModelFile(std::string(source != nullptr ? source : ".") +
                             "/config/robots/kuka_lbr_iiwa_r840.yaml");
  EXPECT_TRUE(robot.ok());
  RobotModel model = robot->model;
  model.tool.y = -0.045;
  model.tool.z = 0.2;
  model.link_radius = kLinkRadius;
  return model;
}

std::vector<double> NormalizedParameters(const RobotModel& model) {
  std::vector<double> k_hat = ToParameterVector(model);
  NormalizeTranslationParameters(k_hat, model.JointCount(), kScale);
  return k_hat;
}

// Around each link's middle: points on its surface, and points 0.3 m from its axis that are
// 0.15 m or more from every link (the scene near the arm).
std::vector<Sample> SamplesAround(const RobotModel& model, const std::vector<double>& q) {
  const std::vector<double> k = ToParameterVector(model);
  const auto capsules =
      ArmCapsules(ComputeJointFrames(JointTypes(model), k.data(), q.data()), kLinkRadius);
  std::vector<Sample> samples;
  for (const Capsule& capsule : capsules) {
    const Eigen::Vector3d axis = (capsule.b - capsule.a).normalized();
    const Eigen::Vector3d u = axis.unitOrthogonal(), v = axis.cross(u);
    for (int step = 0; step < 12; ++step) {
      const double angle = step * M_PI / 6;
      const Eigen::Vector3d out = std::cos(angle) * u + std::sin(angle) * v;
      const Eigen::Vector3d middle = 0.5 * (capsule.a + capsule.b);
      samples.push_back({middle + kLinkRadius * out, true});
      const Eigen::Vector3d far = middle + 0.3 * out;
      double nearest = 1e9;
      for (const Capsule& other : capsules) nearest = std::min(nearest, other.AxisDistance(far));
      if (nearest > 0.15) samples.push_back({far, false});
    }
  }
  return samples;
}

// The samples as a scan of one row, in the sensor frame of `model` at the pose of each point.
Dataset ScanOf(const RobotModel& model, const std::vector<Sample>& samples,
               const std::vector<std::vector<double>>& poses, PoseLayout layout) {
  Dataset dataset;
  dataset.layout = layout;
  dataset.rows = 1;
  dataset.cols = samples.size();
  dataset.joint_count = model.JointCount();
  for (const auto& q : poses)
    dataset.pose_joints.insert(dataset.pose_joints.end(), q.begin(), q.end());
  const Chain chain = ChainOf(model, kScale);
  const std::vector<double> k_hat = NormalizedParameters(model);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const Transform3<double> T_base_sensor = chain.Pose(
        k_hat.data(), dataset.pose_joints.data() + dataset.PoseOf(i) * dataset.joint_count);
    const Eigen::Vector3d p = kScale * (T_base_sensor.inverse() * (samples[i].base_point / kScale));
    dataset.x.push_back(static_cast<float>(p.x()));
    dataset.y.push_back(static_cast<float>(p.y()));
    dataset.z.push_back(static_cast<float>(p.z()));
  }
  return dataset;
}

std::vector<std::uint8_t> MaskAt(const RobotModel& model, const Dataset& dataset,
                                 double margin = kMargin) {
  const Chain chain = ChainOf(model, kScale);
  const std::vector<double> k_hat = NormalizedParameters(model);
  const ProjectedCloud cloud = ProjectDataset(dataset, chain, k_hat.data());
  return PointsOnLinks(dataset, cloud, chain, k_hat.data(),
                       chain.link_radius + margin / chain.scale);
}

void ExpectMaskIsTheLinks(const std::vector<std::uint8_t>& mask,
                          const std::vector<Sample>& samples) {
  ASSERT_EQ(mask.size(), samples.size());
  std::size_t on_links = 0, scene = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    EXPECT_EQ(mask[i] == 1, samples[i].on_link) << "sample " << i;
    (samples[i].on_link ? on_links : scene) += 1;
  }
  EXPECT_GE(on_links, 36u);
  EXPECT_GE(scene, 12u);
}

TEST(LinkMask, RemovesThePointsOnTheLinksAndKeepsTheSceneBeyondThem) {
  const RobotModel model = Iiwa();
  const std::vector<double> q = {0.3, 0.9, -0.4, -1.1, 0.7, 0.8, -0.2};
  const auto samples = SamplesAround(model, q);
  const Dataset scan = ScanOf(model, samples, {q}, PoseLayout::kOnePerScan);
  ExpectMaskIsTheLinks(MaskAt(model, scan), samples);
}

TEST(LinkMask, TheMarginCoversAModelACentimetreOff) {
  const RobotModel truth = Iiwa();
  const std::vector<double> q = {-0.5, 0.6, 0.2, -1.4, -0.3, 1.1, 0.4};
  const auto samples = SamplesAround(truth, q);
  const Dataset scan = ScanOf(truth, samples, {q}, PoseLayout::kOnePerScan);
  RobotModel off = truth;
  off.segments[2].x += 0.006;     // A3 -> A4
  off.segments[4].alpha += 0.01;  // A5 -> A6: about 4 mm at the sensor
  off.tool.z -= 0.005;
  ExpectMaskIsTheLinks(MaskAt(off, scan), samples);
  // Without the margin, points the model places outside the links' surface stay.
  const auto without_margin = MaskAt(off, scan, 0.0);
  std::size_t missed = 0;
  for (std::size_t i = 0; i < samples.size(); ++i)
    missed += samples[i].on_link && without_margin[i] == 0 ? 1 : 0;
  EXPECT_GT(missed, 0u);
}

TEST(LinkMask, FollowsTheArmThroughASweepWithAPosePerPoint) {
  const RobotModel model = Iiwa();
  std::vector<Sample> samples;
  std::vector<std::vector<double>> poses;
  for (int step = 0; step < 8; ++step) {  // A1 and A4 turn by 0.7 rad during the sweep
    const std::vector<double> q = {0.1 * step, 0.9, -0.4, -1.1 + 0.1 * step, 0.7, 0.8, -0.2};
    for (const Sample& sample : SamplesAround(model, q)) {
      samples.push_back(sample);
      poses.push_back(q);
    }
  }
  const Dataset sweep = ScanOf(model, samples, poses, PoseLayout::kOnePerPoint);
  ExpectMaskIsTheLinks(MaskAt(model, sweep), samples);
}

}  // namespace
}  // namespace selfcal::calib
