#include "protocols/scenario/sim_messages.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace selfcal {
namespace {

// Transfer delays between measurement and logging [us]: USB/Ethernet plus driver.
constexpr std::int64_t kLidarDelayUs = 1000;
constexpr std::int64_t kLineDelayUs = 500;
constexpr std::int64_t kCameraDelayUs = 30000;

// A sensor message with the frame's host and device stamps and its counter in `counter`: what
// every sensor's message carries.
template <typename SensorMessage>
SensorMessage StampedMessage(const sim::SimFrame& frame, const MessageContext& context,
                             std::int64_t SensorMessage::*counter) {
  SensorMessage message;
  message.utime = context.start_utime + frame.stamp_us;
  message.device_utime = frame.device_stamp_us;
  message.*counter = frame.counter;
  return message;
}

// One coordinate (0: x, 1: y, 2: z) of each of the frame's points, in their order: a column of a
// points message.
std::vector<float> PointCoordinates(const sim::SimFrame& frame, int axis) {
  std::vector<float> values;
  values.reserve(frame.points.size());
  for (const Eigen::Vector3f& point : frame.points) values.push_back(point[axis]);
  return values;
}

}  // namespace

selfcal::joint_state_t ToJointState(const sim::SimJointState& state,
                                    const MessageContext& context) {
  selfcal::joint_state_t message;
  message.utime = context.start_utime + state.stamp_us;
  message.device_utime = state.device_stamp_us;
  message.num_joints = static_cast<std::int32_t>(state.positions.size());
  message.names = context.joint_names;
  message.positions = state.positions;
  message.velocities = state.velocities;
  message.efforts.assign(state.positions.size(), std::numeric_limits<double>::quiet_NaN());
  return message;
}

selfcal::scan_marker_t ToScanMarker(const sim::SimMarker& marker, const MessageContext& context) {
  selfcal::scan_marker_t message;
  message.utime = context.start_utime + marker.stamp_us;
  message.event = marker.begin ? selfcal::scan_marker_t::BEGIN : selfcal::scan_marker_t::END;
  message.purpose = marker.purpose == sim::ScanPurpose::kFit ? selfcal::scan_marker_t::FIT
                                                             : selfcal::scan_marker_t::VALIDATION;
  message.scan_index = marker.scan_index;
  message.plan_name = context.plan_name;
  message.session_id = context.session_id;
  return message;
}

selfcal::range_scan_t ToRangeScan(const sim::SimFrame& frame, const MessageContext& context) {
  auto message = StampedMessage(frame, context, &selfcal::range_scan_t::scan_counter);
  message.time_per_ray = context.sensor.time_per_ray;
  message.angle_first = context.sensor.angle_first;
  message.angle_increment = context.sensor.angle_increment;
  message.num_ranges = static_cast<std::int32_t>(frame.ranges.size());
  message.ranges = frame.ranges;
  message.num_intensities = 0;
  return message;
}

selfcal::line_profile_t ToLineProfile(const sim::SimFrame& frame, const MessageContext& context) {
  auto message = StampedMessage(frame, context, &selfcal::line_profile_t::device_counter);
  message.num_points = static_cast<std::int32_t>(frame.points.size());
  message.x = PointCoordinates(frame, 0);
  message.z = PointCoordinates(frame, 2);
  // A plain reflectance: the simulator has no material model.
  message.intensity.reserve(frame.points.size());
  for (const float z : message.z) message.intensity.push_back(std::isnan(z) ? 0.0f : 512.0f);
  return message;
}

namespace {

// The stamps, counter and size a depth image and an organized cloud both carry.
template <typename CameraMessage>
CameraMessage CameraFrameHeader(const sim::SimFrame& frame, const MessageContext& context) {
  auto message = StampedMessage(frame, context, &CameraMessage::frame_counter);
  message.width = context.sensor.width;
  message.height = context.sensor.height;
  return message;
}

}  // namespace

selfcal::depth_image_t ToDepthImage(const sim::SimFrame& frame, const MessageContext& context) {
  auto message = CameraFrameHeader<selfcal::depth_image_t>(frame, context);
  message.depth_unit_m = 0.001;
  message.fx = context.sensor.intrinsics.fx;
  message.fy = context.sensor.intrinsics.fy;
  message.cx = context.sensor.intrinsics.cx;
  message.cy = context.sensor.intrinsics.cy;
  message.num_pixels = static_cast<std::int32_t>(frame.points.size());
  message.depth.resize(frame.points.size());
  for (std::size_t i = 0; i < frame.points.size(); ++i) {
    const double z = frame.points[i].z();
    const double counts = std::isnan(z) ? 0.0 : std::round(z / message.depth_unit_m);
    const auto value =
        (counts >= 1 && counts <= 65535) ? static_cast<std::uint16_t>(counts) : std::uint16_t{0};
    message.depth[i] = static_cast<std::int16_t>(value);  // the bits of a uint16 (see the .lcm)
  }
  return message;
}

selfcal::organized_cloud_t ToOrganizedCloud(const sim::SimFrame& frame,
                                            const MessageContext& context) {
  auto message = CameraFrameHeader<selfcal::organized_cloud_t>(frame, context);
  message.num_points = static_cast<std::int32_t>(frame.points.size());
  message.x = PointCoordinates(frame, 0);
  message.y = PointCoordinates(frame, 1);
  message.z = PointCoordinates(frame, 2);
  message.num_intensities = 0;
  return message;
}

std::vector<LogEvent> SegmentEvents(const sim::SimSegment& segment, const MessageContext& context) {
  std::vector<LogEvent> events;
  events.reserve(segment.joint_states.size() + segment.markers.size() + segment.frames.size());
  auto add = [&](const std::string& channel, std::int64_t utime, std::vector<std::uint8_t> data) {
    LogEvent event;
    event.utime = utime;
    event.channel = channel;
    event.data = std::move(data);
    events.push_back(std::move(event));
  };
  for (const auto& state : segment.joint_states) {
    const auto message = ToJointState(state, context);
    add(context.channels.joint_state, message.utime, EncodeLcm(message));
  }
  for (const auto& marker : segment.markers) {
    const auto message = ToScanMarker(marker, context);
    add(context.channels.scan_marker, message.utime, EncodeLcm(message));
  }
  for (const auto& frame : segment.frames) {
    switch (context.sensor.kind) {
      case SensorLayout::kRotatingLidar: {
        const auto message = ToRangeScan(frame, context);
        const auto last_ray_us = static_cast<std::int64_t>(
            std::ceil(1e6 * (context.sensor.width - 1) * context.sensor.time_per_ray));
        add(context.channels.range_scan, message.utime + last_ray_us + kLidarDelayUs,
            EncodeLcm(message));
        break;
      }
      case SensorLayout::kLineScanner: {
        const auto message = ToLineProfile(frame, context);
        add(context.channels.line_profile, message.utime + kLineDelayUs, EncodeLcm(message));
        break;
      }
      case SensorLayout::kDepthCamera:
        if (context.camera_output == CameraOutput::kDepthImage) {
          const auto message = ToDepthImage(frame, context);
          add(context.channels.depth_image, message.utime + kCameraDelayUs, EncodeLcm(message));
        } else {
          const auto message = ToOrganizedCloud(frame, context);
          add(context.channels.organized_cloud, message.utime + kCameraDelayUs, EncodeLcm(message));
        }
        break;
    }
  }
  std::stable_sort(events.begin(), events.end(),
                   [](const LogEvent& a, const LogEvent& b) { return a.utime < b.utime; });
  return events;
}

}  // namespace selfcal
