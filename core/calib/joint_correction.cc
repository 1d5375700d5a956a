#include "core/calib/joint_correction.h"

#include <algorithm>
#include <cmath>

#include "core/model/gravity.h"
#include "core/model/kinematics.h"

namespace selfcal::calib {

void JointCorrection::Apply(std::span<const JointType> joint_types, const double* q,
                            const double* theta_hat, double* q_eff, double* columns) const {
  std::copy(q, q + joint_types.size(), q_eff);
  if (Empty()) return;
  const JointFrames frames = ComputeJointFrames(joint_types, frozen_parameters.data(), q);
  const std::vector<double> torque = GravityTorques(load, frames);
  for (std::size_t c = 0; c < joints.size(); ++c) {
    const double g = torque[joints[c]] / reference_torque[c];
    q_eff[joints[c]] += g * theta_hat[c];
    if (columns != nullptr) columns[c] = g;
  }
}

JointCorrection ElasticityCorrection(const RobotModel& model,
                                     const std::vector<const double*>& configurations) {
  const std::vector<JointType> types = JointTypes(model);
  const std::vector<double> parameters = ToParameterVector(model);
  std::vector<double> largest(types.size(), 0.0);
  for (const double* q : configurations) {
    const std::vector<double> torque =
        GravityTorques(model.gravity, ComputeJointFrames(types, parameters.data(), q));
    for (std::size_t j = 0; j < types.size(); ++j)
      largest[j] = std::max(largest[j], std::abs(torque[j]));
  }
  JointCorrection correction;
  correction.load = model.gravity;
  correction.frozen_parameters = parameters;
  const double overall = *std::max_element(largest.begin(), largest.end());
  for (std::size_t j = 0; j < types.size(); ++j) {
    if (types[j] != JointType::kRevolute || !(largest[j] > 0) ||
        largest[j] < kMinTorqueShare * overall)
      continue;
    correction.joints.push_back(j);
    correction.reference_torque.push_back(largest[j]);
  }
  return correction;
}

}  // namespace selfcal::calib
