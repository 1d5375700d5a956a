// The command-line options of camera::StreamOptions, as the streaming depth cameras
// (selfcal-openni2, selfcal-v4l2) describe them; apart from camera_stream so that the drivers'
// libraries do not link the start-up kit.
#pragma once

#include <string>

#include "protocols/camera/camera_stream.h"
#include "protocols/program/program.h"

namespace selfcal::camera {

// Adds --lcm-url, --channel, --trigger ("none": publish every frame, "request": one frame per
// scan_marker_t BEGIN), --trigger-channel and --max-frames, in this order.
void DescribeRequestStreamOptions(program::Program& p, std::string& lcm_url, std::string& trigger,
                                  StreamOptions& stream);

}  // namespace selfcal::camera
