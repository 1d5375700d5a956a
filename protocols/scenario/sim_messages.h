// Simulated measurements -> the LCM messages and log events of docs/recording.md.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/sim/sensor_model.h"
#include "core/sim/simulator.h"
#include "core/util/expected.h"
#include "protocols/lcm/channels.h"
#include "protocols/lcm_log/lcm_log.h"
#include "protocols/scenario/scenario_file.h"
#include "selfcal/depth_image_t.hpp"
#include "selfcal/joint_state_t.hpp"
#include "selfcal/line_profile_t.hpp"
#include "selfcal/organized_cloud_t.hpp"
#include "selfcal/range_scan_t.hpp"
#include "selfcal/scan_marker_t.hpp"

namespace selfcal {

struct MessageContext {
  std::int64_t start_utime = 0;  // host time [us] of simulated time 0
  std::vector<std::string> joint_names;
  std::string plan_name;
  std::string session_id;
  sim::SensorModel sensor;
  CameraOutput camera_output = CameraOutput::kDepthImage;
  channels::RecordingChannels channels;
};

selfcal::joint_state_t ToJointState(const sim::SimJointState& state, const MessageContext& context);
selfcal::scan_marker_t ToScanMarker(const sim::SimMarker& marker, const MessageContext& context);
selfcal::range_scan_t ToRangeScan(const sim::SimFrame& frame, const MessageContext& context);
selfcal::line_profile_t ToLineProfile(const sim::SimFrame& frame, const MessageContext& context);
// Depth in millimetres (depth_unit_m 0.001), rounded; NaN and depths beyond 65.535 m are 0.
selfcal::depth_image_t ToDepthImage(const sim::SimFrame& frame, const MessageContext& context);
selfcal::organized_cloud_t ToOrganizedCloud(const sim::SimFrame& frame,
                                            const MessageContext& context);

// All events of one segment, ordered by the time they would have been logged: joint states and
// markers at their stamp, sensor messages when their last measurement is complete plus a
// transfer delay (a LiDAR rotation after its last ray). Stable for equal times.
std::vector<LogEvent> SegmentEvents(const sim::SimSegment& segment, const MessageContext& context);

}  // namespace selfcal
