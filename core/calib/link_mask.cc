#include "core/calib/link_mask.h"

#include <algorithm>
#include <cmath>

#include "core/model/arm_capsules.h"

namespace selfcal::calib {
namespace {

constexpr double kJointTolerance = 1e-3;  // rad (m for a prismatic joint, before normalization)

bool MovedBeyond(const double* a, const double* b, std::size_t n) {
  for (std::size_t j = 0; j < n; ++j) {
    if (std::abs(a[j] - b[j]) > kJointTolerance) return true;
  }
  return false;
}

}  // namespace

std::vector<std::uint8_t> PointsOnLinks(const Dataset& dataset, const ProjectedCloud& cloud,
                                        const Chain& chain, const double* k_hat, double radius) {
  std::vector<std::uint8_t> on_links(dataset.PointCount(), 0);
  const std::size_t n = chain.JointCount();
  std::vector<Capsule> capsules;
  double capsules_at[kMaxJoints];  // the raw joints the capsules were computed at
  bool have_capsules = false;
  for (std::size_t i = 0; i < dataset.PointCount(); ++i) {
    if (!cloud.Valid(i)) continue;
    const std::size_t pose = dataset.PoseOf(i);
    double joints[kMaxJoints];
    const PoseState state = dataset.Joints(pose, joints);
    if (!have_capsules || MovedBeyond(state.q, capsules_at, n)) {
      double buffer[64];
      const double* q_hat = chain.EffectiveJoints(k_hat, state, buffer);
      capsules = ArmCapsules(ComputeJointFrames(chain.joint_types, k_hat, q_hat), radius);
      std::copy_n(state.q, n, capsules_at);
      have_capsules = true;
    }
    const Eigen::Vector3d point = cloud.Point(i).cast<double>();
    for (const Capsule& capsule : capsules) {
      if (capsule.AxisDistance(point) < radius) {
        on_links[i] = 1;
        break;
      }
    }
  }
  return on_links;
}

}  // namespace selfcal::calib
