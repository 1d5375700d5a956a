// The selfcal-openni2 process: an OpenNi2Camera (device or .oni playback), reconnection, and
// publication of selfcal.depth_image_t. Buffers are allocated once.
//
// Request mode (--trigger request): OpenNI2 cameras stream and cannot be triggered, so a request
// (selfcal.scan_marker_t BEGIN on the trigger channel) publishes exactly one frame: the first whose
// exposure time is after the request. Otherwise every frame is published.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/timing/clock_filter.h"
#include "core/util/log.h"
#include "drivers/openni2/openni2_camera.h"
#include "protocols/bus/bus.h"
#include "protocols/camera/camera_stream.h"
#include "protocols/camera/frame_clock.h"
#include "protocols/lcm/channels.h"

namespace selfcal::openni2 {

struct DriverOptions {
  CameraOptions camera;
  camera::StreamOptions stream{.channel = channels::kDepthImage};
  bool request_mode = false;
};

struct DriverCounters : camera::StreamCounters {
  std::uint64_t frames = 0;  // received, published or not
};

class OpenNi2Driver {
 public:
  OpenNi2Driver(DriverOptions options, Bus& bus, LogSink logger);
  // Runs until `stop`, max_frames, or the end of a recording. Errors: bus failure, or a
  // recording that cannot be opened or read.
  Status Run(const std::atomic<bool>& stop);
  const DriverCounters& counters() const { return counters_; }

 private:
  bool playback() const { return !options_.camera.oni_path.empty(); }
  // Opens the camera; a failure is an error for a recording only (a device is tried again).
  Status Open();
  // The host time of `frame`'s exposure.
  std::int64_t HostUtime(const DepthFrame& frame);
  // Publishes the frame in the loop's depth buffer; true when max_frames are done.
  Expected<bool> Publish(std::int64_t utime, const DepthFrame& frame);

  DriverOptions options_;
  DriverCounters counters_;
  camera::StreamLoop loop_;
  std::unique_ptr<OpenNi2Camera> camera_;
  timing::ClockFilter clock_{camera::FrameClockOptions()};
  std::int64_t playback_epoch_us_ = 0;  // host time at which a recording started playing
  std::int64_t first_device_us_ = -1;   // the recording's first device time
};

}  // namespace selfcal::openni2
