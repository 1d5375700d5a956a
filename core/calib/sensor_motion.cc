#include "core/calib/sensor_motion.h"

#include <algorithm>
#include <cmath>

#include "core/model/jacobian.h"
#include "core/model/normalization.h"

namespace selfcal::calib {
namespace {

std::vector<std::vector<double>> FitScanConfigurations(const std::vector<Dataset>& datasets,
                                                       std::size_t per_scan) {
  std::vector<std::vector<double>> configurations;
  for (const Dataset& dataset : datasets) {
    if (dataset.validation) continue;
    const std::size_t poses = dataset.PoseCount();
    const std::size_t stride = std::max<std::size_t>(1, poses / per_scan);
    double buffer[kMaxJoints];
    for (std::size_t pose = 0; pose < poses; pose += stride) {
      const double* joints = dataset.JointsOfPose(pose, buffer);
      configurations.emplace_back(joints, joints + dataset.joint_count);
    }
  }
  return configurations;
}

}  // namespace

SensorMotion::SensorMotion(const Chain& chain, const std::vector<std::size_t>& free,
                           const std::vector<Dataset>& datasets)
    : chain_(chain), free_(free), configurations_(FitScanConfigurations(datasets, kPosesPerScan)) {}

Eigen::MatrixXd SensorMotion::Metric(const std::vector<double>& k_hat) const {
  const std::size_t K = chain_.ParameterCount();
  const auto F = static_cast<Eigen::Index>(free_.size());
  if (configurations_.empty()) return Eigen::MatrixXd::Identity(F, F);  // |delta k_hat|
  std::vector<double> k(k_hat.begin(), k_hat.begin() + static_cast<std::ptrdiff_t>(K));
  DenormalizeTranslationParameters(k, chain_.JointCount(), chain_.scale);
  // d k_SI / d k_hat: s for a translation, 1 for an angle.
  std::vector<double> unit(K, 1.0);
  DenormalizeTranslationParameters(unit, chain_.JointCount(), chain_.scale);

  Eigen::MatrixXd metric = Eigen::MatrixXd::Zero(F, F);
  Eigen::MatrixXd columns = Eigen::MatrixXd::Zero(6, F);
  PoseJacobian jacobian;
  for (const std::vector<double>& joints : configurations_) {
    ForwardKinematicsWithJacobian(chain_.joint_types, k, joints, &jacobian);
    for (Eigen::Index c = 0; c < F; ++c) {
      const std::size_t index = free_[static_cast<std::size_t>(c)];
      if (index >= K) continue;
      columns.col(c) = jacobian.col(static_cast<Eigen::Index>(index)) * unit[index];
      columns.col(c).head<3>() /= chain_.scale;
    }
    metric.noalias() += columns.transpose() * columns;
  }
  metric /= static_cast<double>(configurations_.size());
  for (Eigen::Index c = 0; c < F; ++c) {
    if (free_[static_cast<std::size_t>(c)] >= K) metric(c, c) += 1.0;
  }
  return metric;
}

double SensorMotion::Step(const std::vector<double>& before,
                          const std::vector<double>& after) const {
  Eigen::VectorXd step(static_cast<Eigen::Index>(free_.size()));
  for (std::size_t c = 0; c < free_.size(); ++c) {
    step[static_cast<Eigen::Index>(c)] = after[free_[c]] - before[free_[c]];
  }
  return std::sqrt(std::max(0.0, step.dot(Metric(before) * step)));
}

}  // namespace selfcal::calib
