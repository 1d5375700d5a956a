#include "core/sim/ground_truth.h"

#include <algorithm>
#include <cmath>

#include "core/model/kinematics.h"
#include "core/sim/ik.h"
#include "core/sim/random.h"

namespace selfcal::sim {

PoseError SensorPoseError(const RobotModel& truth, const RobotModel& model, int samples,
                          std::uint64_t seed) {
  Random random(SubKey(seed, 0x5a3b1e));
  PoseError error;
  double position_sum = 0, orientation_sum = 0;
  for (int k = 0; k < samples; ++k) {
    const std::vector<double> q = RandomConfiguration(truth, 0.0, random);
    const Eigen::Isometry3d a = ForwardKinematics(truth, q);
    const Eigen::Isometry3d b = ForwardKinematics(model, q);
    const double position = (a.translation() - b.translation()).norm();
    const double orientation = Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
    position_sum += position * position;
    orientation_sum += orientation * orientation;
    error.position_max = std::max(error.position_max, position);
    error.orientation_max = std::max(error.orientation_max, orientation);
  }
  error.position_rms = std::sqrt(position_sum / samples);
  error.orientation_rms = std::sqrt(orientation_sum / samples);
  return error;
}

RobotModel PerturbModel(const RobotModel& nominal, std::uint64_t seed,
                        const PerturbationOptions& options) {
  const std::vector<double> k0 = ToParameterVector(nominal);
  std::vector<double> direction(k0.size(), 0.0);
  Random random(SubKey(seed, 0x7e0757));
  for (std::size_t i = 0; i < k0.size(); ++i) {
    const double g = random.Gaussian();  // drawn for every index: the layout fixes the stream
    if (i >= nominal.mask.size() || !nominal.mask[i]) continue;
    direction[i] =
        g * (IsTranslationParameter(nominal, i) ? options.translation_sigma : options.angle_sigma);
  }
  RobotModel truth = nominal;
  auto apply = [&](double scale) {
    std::vector<double> k = k0;
    for (std::size_t i = 0; i < k.size(); ++i) k[i] += scale * direction[i];
    FromParameterVector(k, truth);
    return SensorPoseError(truth, nominal, options.samples, seed).position_rms;
  };
  // The error grows almost linearly with the scale: a few secant steps reach the target.
  double scale = 1.0;
  for (int iteration = 0; iteration < 8; ++iteration) {
    const double rms = apply(scale);
    if (std::abs(rms - options.target_position_rms) < 0.01 * options.target_position_rms) break;
    if (rms <= 0) break;
    scale *= options.target_position_rms / rms;
  }
  return truth;
}

}  // namespace selfcal::sim
