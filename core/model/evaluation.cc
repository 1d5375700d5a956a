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

struct Accumulator {
  double sum_position_sq = 0, sum_orientation_sq = 0;
  PoseErrorStats stats;
  void Add(const Eigen::Isometry3d& truth, const Eigen::Isometry3d& model) {
    const double position = (truth.translation() - model.translation()).norm();
    const double orientation = RotationAngle(truth.linear(), model.linear());
    sum_position_sq += position * position;
    sum_orientation_sq += orientation * orientation;
    stats.max_position_m = std::max(stats.max_position_m, position);
    stats.max_orientation_rad = std::max(stats.max_orientation_rad, orientation);
  }
  PoseErrorStats Finish(std::size_t count) {
    if (count > 0) {
      stats.rms_position_m = std::sqrt(sum_position_sq / static_cast<double>(count));
      stats.rms_orientation_rad = std::sqrt(sum_orientation_sq / static_cast<double>(count));
    }
    return stats;
  }
};

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

ModelComparison CompareModels(const RobotModel& truth, const RobotModel& model, std::size_t samples,
                              std::uint64_t seed) {
  const std::string problem = CheckComparable(truth, model);
  if (!problem.empty()) {
    std::cerr << "selfcal: CompareModels: " << problem << "\n";
    std::abort();
  }
  const RobotModel flange_model = WithUncalibratedFromTruth(truth, model);
  const std::vector<JointType> types = JointTypes(truth);
  const std::vector<double> k_truth = ToParameterVector(truth);
  const std::vector<double> k_model = ToParameterVector(model);
  const std::vector<double> k_flange = ToParameterVector(flange_model);

  Accumulator sensor, flange;
  for (const auto& q : RandomConfigurations(truth, samples, seed)) {
    const auto T_truth = ForwardKinematics<double, double>(types, k_truth.data(), q.data());
    sensor.Add(T_truth, ForwardKinematics<double, double>(types, k_model.data(), q.data()));
    flange.Add(T_truth, ForwardKinematics<double, double>(types, k_flange.data(), q.data()));
  }
  ModelComparison result;
  result.samples = samples;
  result.seed = seed;
  result.sensor = sensor.Finish(samples);
  result.flange = flange.Finish(samples);
  return result;
}

}  // namespace selfcal
