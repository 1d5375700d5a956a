// The selfcal-openni2 process: an OpenNi2Camera (device or .oni playback), reconnection, and
// publication of selfcal.depth_image_t. Buffers are allocated once.
//
// Request mode (--trigger request): OpenNI2 cameras stream and cannot be triggered, so a request
// (selfcal.scan_marker_t BEGIN on the trigger channel) publishes exactly one frame: the first whose
// exposure time is after the request. Otherwise every frame is published.
#pragma once

#include <atomic>
#include <chrono>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/timing/clock_filter.h"
#include "core/util/log.h"
#include "drivers/openni2/openni2_camera.h"
#include "protocols/bus/bus.h"
#include "protocols/camera/camera_stream.h"
#include "protocols/camera/depth_image_publisher.h"
#include "protocols/camera/frame_clock.h"

namespace selfcal::openni2 {

struct DriverOptions {
  CameraOptions camera;
  camera::StreamOptions stream{.channel = "SELFCAL_DEPTH_IMAGE"};
  bool request_mode = false;
};

struct DriverCounters {
  std::uint64_t published = 0;
  std::uint64_t requests = 0;
  std::uint64_t frames = 0;
  std::uint64_t reconnects = 0;
};

class OpenNi2Driver {
 public:
  OpenNi2Driver(DriverOptions options, Bus& bus, LogSink logger);
  // Runs until `stop`, max_frames, or the end of a recording. Errors: bus failure, or a
  // recording that cannot be opened or read.
  Status Run(const std::atomic<bool>& stop);
  const DriverCounters& counters() const { return counters_; }

 private:
  Status Publish(std::int64_t utime, const DepthFrame& frame);

  DriverOptions options_;
  Bus& bus_;
  LogSink log_;
  std::unique_ptr<OpenNi2Camera> camera_;
  std::vector<std::int16_t> depth_;
  camera::DepthImagePublisher publisher_;
  timing::ClockFilter clock_{camera::FrameClockOptions()};
  std::deque<std::int64_t> requests_;  // utimes of pending requests
  DriverCounters counters_;
};

}  // namespace selfcal::openni2
