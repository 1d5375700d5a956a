// The arm's links as capsules: the one home of the link geometry that the simulator draws (the
// arm seeing itself, core/sim/field_effects.h), the planner keeps clear of obstacles
// (core/sim/scan_plan.h) and the engine removes from the scans (core/calib/link_mask.h).
//
// A capsule per link: from the base origin to the first joint's origin, then between consecutive
// distinct joint origins, then on to the tool point (the sensor's origin). One radius for all:
// an approximation of the links' meshes, not the meshes.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/model/gravity.h"

namespace selfcal {

struct Capsule {
  Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
  double radius = 0;
  // Distance from `point` to the capsule's axis segment a-b (inside the capsule: < radius).
  double AxisDistance(const Eigen::Vector3d& point) const;
};

// The links of one configuration (joint_frames of gravity.h), in the units of `frames`.
std::vector<Capsule> ArmCapsules(const JointFrames& frames, double radius);

}  // namespace selfcal
