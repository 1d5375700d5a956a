// Feeds a SceneRangeSource from the bus: selfcal.joint_state_t messages (SELFCAL_JOINT_STATE),
// joints matched to the robot model by name (by order when the message has no names), and
// selfcal.scan_marker_t (SELFCAL_SCAN_MARKER); utime (CLOCK_REALTIME) converted to the
// simulator's CLOCK_MONOTONIC.
#pragma once

#include <string>

#include "protocols/bus/bus.h"
#include "tools/sim_scip/scene_range_source.h"

namespace selfcal::sim_scip {

// Subscribes; messages are handled whenever the caller runs bus.HandleOnce(). Malformed
// messages and unknown joint names are counted in `*rejected` (when given) and ignored.
void FeedJointStates(Bus& bus, const std::string& channel, SceneRangeSource& source,
                     std::int64_t* rejected = nullptr);
// The same for scan markers (a malformed one counts in `*rejected`).
void FeedScanMarkers(Bus& bus, const std::string& channel, SceneRangeSource& source,
                     std::int64_t* rejected = nullptr);

}  // namespace selfcal::sim_scip
