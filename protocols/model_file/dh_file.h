// Standard Denavit-Hartenberg tables as YAML, for importing robots into MCPC
// (core/model/chain.h: DhTable, DhToChain, ChainToMcpc). Read strictly like the model file.
//
//   name: ur5
//   base: {xyz: [0, 0, 0], rpy: [0, 0, 0]}   # optional: base to DH frame 0 (URDF origin rules)
//   tool: {xyz: [0, 0, 0], rpy: [0, 0, 0]}   # optional: DH frame n to the tool
//   joints:                                  # one row per joint, base to tip
//     - {name: J1, type: revolute, d: 0.089159, theta: 0, a: 0, alpha: 1.5707963267948966,
//        lower: -6.2832, upper: 6.2832, max_velocity: 3.1416, max_acceleration: 5.0}
//
// A row is T_{i-1,i} = rot_z(theta + q) trans_z(d) trans_x(a) rot_x(alpha) (prismatic: d + q);
// m and rad. rpy as in URDF: R = rot_z(yaw) rot_y(pitch) rot_x(roll), applied after xyz.
#pragma once

#include <string>

#include "core/model/chain.h"
#include "core/util/expected.h"

namespace selfcal {

Expected<DhTable> ParseDhFile(const std::string& text, const std::string& name);
Expected<DhTable> ReadDhFile(const std::string& path);

}  // namespace selfcal
