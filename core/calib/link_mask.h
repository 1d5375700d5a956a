// DELIBERATE DEVIATION (docs/engine.md, deviation 20), not in the paper: the points a sensor sees
// on its own arm are removed before matching. They move with the arm, not with the scene, so ICP
// would pair them with the scene (or with the same link seen from another pose) and pull the
// model towards a wrong solution. Where the robot model gives its links' radius
// (RobotModel::link_radius, the `links:` block of the model file), every point within that radius
// plus a margin of a link's capsule (core/model/arm_capsules.h) at its own pose is removed; the
// margin covers the model's error at the start, where the mask is computed.
#pragma once

#include <cstdint>
#include <vector>

#include "core/calib/chain.h"
#include "core/calib/dataset.h"
#include "core/calib/projection.h"

namespace selfcal::calib {

// 1 for every valid point of `cloud` (`dataset` projected at `k_hat`) whose distance to the axis
// of one of its pose's link capsules at `k_hat` is below `radius` (normalized units), 0 otherwise.
// The capsules are computed again only when a joint moved more than 1 mrad (or 1 mm) since they
// last were: within a LiDAR rotation they stay where they are to about a millimetre.
std::vector<std::uint8_t> PointsOnLinks(const Dataset& dataset, const ProjectedCloud& cloud,
                                        const Chain& chain, const double* k_hat, double radius);

}  // namespace selfcal::calib
