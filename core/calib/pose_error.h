// RMS error of the sensor pose T_base_sensor between two models over configurations drawn
// uniformly within the joint limits (fixed seed): what `selfcal evaluate` reports, here so that
// the engine's tests and benchmarks can measure accuracy against a simulated truth.
#pragma once

#include <cmath>
#include <random>
#include <utility>

#include "core/model/kinematics.h"

namespace selfcal::calib {

struct PoseError {
  double position_m = 0;
  double orientation_rad = 0;
};

inline PoseError SensorPoseError(const RobotModel& a, const RobotModel& b, int configurations = 500,
                                 unsigned seed = 42) {
  std::mt19937 random(seed);
  double position = 0, orientation = 0;
  std::vector<double> q(a.JointCount());
  for (int c = 0; c < configurations; ++c) {
    for (std::size_t j = 0; j < q.size(); ++j) {
      q[j] = std::uniform_real_distribution<double>(a.joints[j].lower, a.joints[j].upper)(random);
    }
    const auto Ta = ForwardKinematics(a, q);
    const auto Tb = ForwardKinematics(b, q);
    position += (Ta.translation() - Tb.translation()).squaredNorm();
    const double angle = Eigen::AngleAxisd(Ta.linear().transpose() * Tb.linear()).angle();
    orientation += angle * angle;
  }
  return {std::sqrt(position / configurations), std::sqrt(orientation / configurations)};
}

}  // namespace selfcal::calib
