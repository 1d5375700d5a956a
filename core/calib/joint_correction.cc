#include "core/calib/joint_correction.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/model/gravity.h"
#include "core/model/kinematics.h"

namespace selfcal::calib {

// The latency column of a pose, or -1 (another recording, or no joint timing).
long JointCorrection::LatencyColumnOf(const PoseState& state) const {
  if (state.series == nullptr) return -1;
  for (std::size_t l = 0; l < latency_recordings.size(); ++l) {
    if (latency_recordings[l] == state.recording) return static_cast<long>(joints.size() + l);
  }
  return -1;
}

void JointCorrection::Apply(std::span<const JointType> joint_types, const PoseState& state,
                            const double* theta_hat, double* q_eff, double* G) const {
  const std::size_t n = joint_types.size();
  if (G != nullptr) std::fill(G, G + n * Count(), 0.0);
  // The latency first: the joints at measurement time + latency, re-interpolated.
  const long latency = LatencyColumnOf(state);
  const std::span<double> q(q_eff, n);
  if (latency >= 0) {
    const double utime = state.utime + 1e6 * theta_hat[latency];
    JointsAt(*state.series, utime, q);
    if (G != nullptr) {  // d q / d latency: the joint velocity there
      JointVelocitiesAt(*state.series, utime, kVelocityHalfWindowUs,
                        std::span<double>(G + static_cast<std::size_t>(latency) * n, n));
    }
  } else {
    std::copy(state.q, state.q + n, q_eff);
  }
  if (joints.empty() && held_compliance.empty()) return;
  // The torque at the joints before the deflection is added.
  const JointFrames frames = ComputeJointFrames(joint_types, frozen_parameters.data(), q_eff);
  const std::vector<double> torque = GravityTorques(load, frames);
  for (std::size_t c = 0; c < joints.size(); ++c) {
    const double g = torque[joints[c]] / reference_torque[c];
    q_eff[joints[c]] += g * theta_hat[c];
    if (G != nullptr) G[c * n + joints[c]] = g;
  }
  for (std::size_t j = 0; j < held_compliance.size() && j < n; ++j)
    q_eff[j] += held_compliance[j] * torque[j];
}

bool HasCompliance(const RobotModel& model) {
  return std::any_of(model.compliance.begin(), model.compliance.end(),
                     [](double c) { return c != 0.0; });
}

JointCorrection HeldCompliance(const RobotModel& model) {
  JointCorrection correction;
  correction.load = model.gravity;
  correction.frozen_parameters = ToParameterVector(model);
  correction.held_compliance = model.compliance;
  return correction;
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

std::vector<double> LowerBounds(const JointCorrection& correction, std::size_t first_column,
                                const std::vector<std::size_t>& free) {
  std::vector<double> lower(free.size(), -std::numeric_limits<double>::infinity());
  for (std::size_t c = 0; c < free.size(); ++c) {
    if (free[c] >= first_column && free[c] - first_column < correction.ElasticityCount())
      lower[c] = 0.0;
  }
  return lower;
}

std::size_t AddLatencyColumns(const std::vector<Dataset>& datasets, JointCorrection& correction) {
  std::size_t added = 0;
  for (const Dataset& dataset : datasets) {
    if (dataset.validation || !dataset.HasJointTiming()) continue;
    const auto& recordings = correction.latency_recordings;
    if (std::find(recordings.begin(), recordings.end(), dataset.recording) != recordings.end())
      continue;
    correction.latency_recordings.push_back(dataset.recording);
    correction.latency_start_s.push_back(dataset.joint_latency_s);
    ++added;
  }
  return added;
}

}  // namespace selfcal::calib
