// Joint zero offsets between two models of the same arm, as a controller takes them: the offsets
// delta with which the nominal kinematics at q + delta puts the sensor where the calibrated
// kinematics at q puts it, up to a constant change of the sensor mount. MCPC has no explicit zero
// offsets (st() between joints has no rotation about z), so an offset shows up spread over the
// segments down the chain; this fit gathers it back per axis. What offsets and a mount change
// cannot explain (a link that changed length, a bent axis) is left in the fit's residual.
//
// The last joint's offset is the sensor mount turning about that joint's axis: the two cannot be
// told apart from the sensor's poses, so it is always 0 here and is part of the mount change.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/model/robot_model.h"
#include "core/util/expected.h"

namespace selfcal {

struct JointOffsetFit {
  // Per joint, base to tip: rad for revolute joints, m for prismatic ones; the last one 0 (above).
  // Add to a measured joint position before evaluating the nominal kinematics.
  std::vector<double> offsets;
  // The sensor mount change that goes with them: its translation and rotation vector (in the
  // sensor frame), and their norms.
  Eigen::Vector3d mount_shift = Eigen::Vector3d::Zero();  // m
  Eigen::Vector3d mount_turn = Eigen::Vector3d::Zero();   // rad
  double mount_shift_m = 0;
  double mount_turn_rad = 0;
  // What offsets and mount leave unexplained, at the sensor over the fit's configurations.
  double rms_position_m = 0;
  double rms_orientation_rad = 0;
  std::size_t samples = 0;
};

// Least squares (Gauss-Newton) over `samples` configurations drawn within the nominal's limits
// (RandomConfigurations, seeded). The models must be comparable (CheckComparable; abort if not).
JointOffsetFit FitJointOffsets(const RobotModel& nominal, const RobotModel& calibrated,
                               std::size_t samples = 200, std::uint64_t seed = 1);

// The model whose kinematics at q are `model`'s at q + offsets (per joint, base to tip: rad or m):
// each joint turned (or shifted) at its zero in the generic chain, then back to MCPC (ChainToMcpc),
// which spreads an offset over the segments down the chain. The mask is `model`'s. What a motor or
// gearbox swap does to an arm: the encoder reads q where the joint stands at q + offset. Errors:
// wrong count, or a chain ChainToMcpc refuses (non-finite parameters).
Expected<RobotModel> WithJointOffsets(const RobotModel& model, const std::vector<double>& offsets);

// The mask of a quick remastering (`selfcal calibrate --mode remaster`): the parameters that the
// joints' zero offsets move, to first order (the derivative of WithJointOffsets at zero, any entry
// of at least kRemasterSensitivity rad or m per rad), plus the sensor mount (the tool's six, which
// also hold the last joint's offset); all within `model.mask`, so the offset of joint 1, which
// turns the arm and the scene it sees together about the base's z axis, stays out (the first
// segment's beta, not observable) as does anything the model file does not calibrate. For axes at
// right angles a zero offset is exactly the segment's beta; for parallel axes it turns x and y.
inline constexpr double kRemasterSensitivity = 1e-3;
Expected<std::vector<bool>> RemasterMask(const RobotModel& model);

}  // namespace selfcal
