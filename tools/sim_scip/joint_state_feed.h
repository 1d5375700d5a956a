// Feeds a SceneRangeSource from selfcal.joint_state_t messages on the bus (SELFCAL_JOINT_STATE):
// joints matched to the robot model by name (by order when the message has no names), utime
// (CLOCK_REALTIME) converted to the simulator's CLOCK_MONOTONIC.
#pragma once

#include <string>

#include "protocols/bus/bus.h"
#include "tools/sim_scip/scene_range_source.h"

namespace selfcal::sim_scip {

// Subscribes; messages are handled whenever the caller runs bus.HandleOnce(). Malformed
// messages and unknown joint names are counted in `*rejected` (when given) and ignored.
void FeedJointStates(Bus& bus, const std::string& channel, SceneRangeSource& source,
                     std::int64_t* rejected = nullptr);

}  // namespace selfcal::sim_scip
