// Conversion between the MCPC model and the serial-chain forms other descriptions use (URDF joint
// origins and axes, Denavit-Hartenberg tables). docs/kinematics.md, "Import and export".
//
// A generic chain is
//   T_base_tip(q) = F_0 * M_1(q_1) * F_1 * M_2(q_2) * ... * M_n(q_n) * F_n
// with F_i fixed isometries and M_i a rotation by q_i about the unit axis a_i through the origin
// of its frame (revolute) or a translation by q_i along a_i (prismatic). URDF is this form with
// F_0 = origin of joint 1, F_i = origin of joint i + 1 (fixed joints folded in), F_n = fixed joints
// to the tip link; standard DH is F_i = rot_z(theta_i) trans_z(d_i) trans_x(a_i) rot_x(alpha_i).
#pragma once

#include <Eigen/Geometry>
#include <span>
#include <string>
#include <vector>

#include "core/model/robot_model.h"
#include "core/util/expected.h"

namespace selfcal {

struct ChainJoint {
  JointSpec spec;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // in the joint's frame; need not be unit
};

struct GenericChain {
  std::string name;
  std::vector<ChainJoint> joints;        // n, base to tip
  std::vector<Eigen::Isometry3d> fixed;  // n + 1: F_0 .. F_n
};

// T_base_tip(q) of the generic chain, composed directly (the reference the conversions are tested
// against). Sizes are checked (abort).
Eigen::Isometry3d ChainForwardKinematics(const GenericChain& chain, std::span<const double> q);

struct McpcConversion {
  RobotModel model;                // mask: the paper's default
  std::vector<std::string> notes;  // what the conversion chose or could not keep, for the user
};

// The MCPC model with the same forward kinematics for every q (to rounding). Construction
// (the paper's "Fundamentals" and DESIGN.md): every MCPC joint frame Z_i has its z axis on joint
// axis i (same direction) and, for revolute joints, its origin on the axis line. Z_1 sits at the
// foot of the common normal of axes 1 and 2 with x along a_1 x a_2, so that the first segment's
// beta and y, which the paper cannot calibrate, are 0 and the base st(s_0) absorbs the rest;
// parallel (or nearly parallel) first axes put Z_1 at the joint frame's origin with x toward
// axis 2. Each Z_{i+1} is Z_i rotated about x then y to align z with axis i + 1, then shifted
// along the new x and y onto the axis; the offset along axis i + 1 is absorbed by the successor
// (for a prismatic successor the shift is zero and the offset moves on down the chain).
// The last transform st(s_n) holds the remaining six degrees of freedom to the tip.
// Errors: no joints, wrong counts, a zero or non-finite axis, non-finite transforms.
Expected<McpcConversion> ChainToMcpc(const GenericChain& chain);

// The generic chain of an MCPC model: F_i = st(s_i), axes z. Exact (no conversion).
GenericChain McpcToChain(const RobotModel& model);

// A row of a standard (distal) Denavit-Hartenberg table:
//   T_{i-1,i} = rot_z(theta + q) * trans_z(d) * trans_x(a) * rot_x(alpha)   (revolute)
//   T_{i-1,i} = rot_z(theta) * trans_z(d + q) * trans_x(a) * rot_x(alpha)   (prismatic)
struct DhRow {
  JointSpec joint;
  double d = 0, theta = 0, a = 0, alpha = 0;  // m, rad, m, rad
};

struct DhTable {
  std::string name;
  Eigen::Isometry3d T_base_frame0 = Eigen::Isometry3d::Identity();  // base to DH frame 0
  std::vector<DhRow> rows;                                          // joints 1..n
  Eigen::Isometry3d T_framen_tool = Eigen::Isometry3d::Identity();  // DH frame n to the tool
};

GenericChain DhToChain(const DhTable& table);

// rot_x(alpha) rot_y(beta) rot_z(gamma) trans(x, y, z) parameters of an isometry, and back.
// The angle decomposition is numerically stable everywhere; at beta = +-90 deg it puts all of the
// ambiguous rotation into gamma (alpha = 0).
FullTransformParams ToFullTransformParams(const Eigen::Isometry3d& T);
Eigen::Isometry3d FromFullTransformParams(const FullTransformParams& p);

}  // namespace selfcal
