#include "core/model/evaluation.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <random>

#include "core/model/kinematics.h"

namespace selfcal {
namespace {

// Angle of R_a^T R_b, from the quaternion: accurate for small angles, unlike acos of the trace.
double RotationAngle(const Eigen::Matrix3d& R_a, const Eigen::Matrix3d& R_b) {
  const Eigen::Quaterniond q(R_a.transpose() * R_b);
  return 2.0 * std::atan2(q.vec().norm(), std::abs(q.w()));
}

}  // namespace

std::string CheckComparable(const RobotModel& truth, const RobotModel& model) {
  if (truth.JointCount() != model.JointCount()) {
    return "the truth has " + std::to_string(truth.JointCount()) + " joints, the model " +
           std::to_string(model.JointCount());
  }
  for (std::size_t i = 0; i < truth.JointCount(); ++i) {
    const JointSpec& a = truth.joints[i];
    const JointSpec& b = model.joints[i];
    if (a.name != b.name) {
      return "joint " + std::to_string(i + 1) + " is '" + a.name + "' in the truth and '" + b.name +
             "' in the model";
    }
    if (a.type != b.type) return "joint " + a.name + " has different types in truth and model";
  }
  if (model.mask.size() != model.ParameterCount()) return "the model's mask has the wrong size";
  return {};
}

std::vector<std::vector<double>> RandomConfigurations(const RobotModel& model, std::size_t count,
                                                      std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<std::vector<double>> configurations(count, std::vector<double>(model.JointCount()));
  for (auto& q : configurations) {
    for (std::size_t i = 0; i < q.size(); ++i) {
      std::uniform_real_distribution<double> uniform(model.joints[i].lower, model.joints[i].upper);
      q[i] = uniform(rng);
    }
  }
  return configurations;
}

RobotModel WithUncalibratedFromTruth(const RobotModel& truth, const RobotModel& model) {
  std::vector<double> k = ToParameterVector(model);
  const std::vector<double> k_truth = ToParameterVector(truth);
  const std::size_t tool = ToolOffset(model.JointCount());
  for (std::size_t i = 0; i < k.size(); ++i) {
    const bool base_or_tool = i < kFullTransformParamCount || i >= tool;
    if (base_or_tool || !model.mask[i]) k[i] = k_truth[i];
  }
  RobotModel result = model;
  FromParameterVector(k, result);
  return result;
}

PoseErrorStats SensorPoseError(const RobotModel& truth, const RobotModel& model,
                               std::span<const std::vector<double>> configurations) {
  if (truth.JointCount() != model.JointCount()) {
    std::cerr << "selfcal: SensorPoseError: the truth has " << truth.JointCount()
              << " joints, the model " << model.JointCount() << "\n";
    std::abort();
  }
  const std::vector<JointType> types = JointTypes(truth);
  const std::vector<double> k_truth = ToParameterVector(truth);
  const std::vector<double> k_model = ToParameterVector(model);
  PoseErrorStats stats;
  double sum_position_sq = 0, sum_orientation_sq = 0;
  for (const std::vector<double>& q : configurations) {
    if (q.size() != truth.JointCount()) {
      std::cerr << "selfcal: SensorPoseError: " << q.size() << " joint positions for "
                << truth.JointCount() << " joints\n";
      std::abort();
    }
    const auto T_truth = ForwardKinematics<double, double>(types, k_truth.data(), q.data());
    const auto T_model = ForwardKinematics<double, double>(types, k_model.data(), q.data());
    const double position = (T_truth.translation() - T_model.translation()).norm();
    const double orientation = RotationAngle(T_truth.linear(), T_model.linear());
    sum_position_sq += position * position;
    sum_orientation_sq += orientation * orientation;
    stats.max_position_m = std::max(stats.max_position_m, position);
    stats.max_orientation_rad = std::max(stats.max_orientation_rad, orientation);
  }
  if (!configurations.empty()) {
    const auto count = static_cast<double>(configurations.size());
    stats.rms_position_m = std::sqrt(sum_position_sq / count);
    stats.rms_orientation_rad = std::sqrt(sum_orientation_sq / count);
  }
  return stats;
}

PoseErrorStats SensorPoseError(const RobotModel& truth, const RobotModel& model,
                               std::size_t samples, std::uint64_t seed) {
  return SensorPoseError(truth, model, RandomConfigurations(truth, samples, seed));
}

ModelComparison CompareModels(const RobotModel& truth, const RobotModel& model, std::size_t samples,
                              std::uint64_t seed) {
  const std::string problem = CheckComparable(truth, model);
  if (!problem.empty()) {
    std::cerr << "selfcal: CompareModels: " << problem << "\n";
    std::abort();
  }
  const std::vector<std::vector<double>> configurations =
      RandomConfigurations(truth, samples, seed);
  ModelComparison result;
  result.samples = samples;
  result.seed = seed;
  result.sensor = SensorPoseError(truth, model, configurations);
  result.flange = SensorPoseError(truth, WithUncalibratedFromTruth(truth, model), configurations);
  return result;
}

std::vector<LinkChange> LinkChanges(const RobotModel& before, const RobotModel& after) {
  const std::vector<double> k_before = ToParameterVector(before),
                            k_after = ToParameterVector(after);
  const std::size_t n = before.JointCount();
  const auto name = [&](std::size_t offset) {
    const std::string parameter = ParameterName(before, offset);
    return parameter.substr(0, parameter.rfind('.'));
  };
  const auto change = [&](const std::string& link, const Transform3<double>& from,
                          const Transform3<double>& to) {
    return LinkChange{link, Eigen::AngleAxisd(from.linear().transpose() * to.linear()).angle(),
                      (to.translation() - from.translation()).norm()};
  };
  std::vector<LinkChange> changes{change(name(kBaseOffset),
                                         FullTransform(k_before.data() + kBaseOffset),
                                         FullTransform(k_after.data() + kBaseOffset))};
  for (std::size_t i = 0; i + 1 < n; ++i) {
    changes.push_back(change(name(SegmentOffset(i)),
                             SegmentTransform(k_before.data() + SegmentOffset(i)),
                             SegmentTransform(k_after.data() + SegmentOffset(i))));
  }
  changes.push_back(change(name(ToolOffset(n)), FullTransform(k_before.data() + ToolOffset(n)),
                           FullTransform(k_after.data() + ToolOffset(n))));
  return changes;
}

}  // namespace selfcal
