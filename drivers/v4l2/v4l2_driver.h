// The selfcal-v4l2 process: a V4l2Camera, reopening a device that failed, and publication of
// selfcal.depth_image_t with the intrinsics from configuration (UVC does not report them).
// Request mode as in selfcal-openni2: one published frame per scan_marker_t BEGIN, the first
// exposed after the request.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/camera/pinhole_intrinsics.h"
#include "core/util/log.h"
#include "drivers/v4l2/v4l2_camera.h"
#include "protocols/bus/bus.h"
#include "protocols/camera/camera_stream.h"
#include "protocols/lcm/channels.h"

namespace selfcal::v4l2 {

struct DriverOptions {
  CameraOptions camera;
  PinholeIntrinsics intrinsics;
  double depth_unit_m = 0.001;
  camera::StreamOptions stream{.channel = channels::kDepthImage};
  bool request_mode = false;
};

struct DriverCounters : camera::StreamCounters {
  std::uint64_t dropped = 0;        // frames the cameras dropped (V4l2Camera counters)
  std::uint64_t sequence_gaps = 0;  // frames skipped (sequence jumps)
};

class V4l2Driver {
 public:
  V4l2Driver(DriverOptions options, V4l2Io& io, Bus& bus, LogSink logger);
  Status Run(const std::atomic<bool>& stop);
  const DriverCounters& counters() const { return counters_; }

 private:
  void Open();
  // Publishes the frame in the loop's depth buffer; true when max_frames are done.
  Expected<bool> Publish(const Frame& frame);
  // Closes the camera (it is opened again every reconnect_period), keeping its counters.
  void Close(const std::string& why);
  void KeepCameraCounters();

  DriverOptions options_;
  V4l2Io& io_;
  DriverCounters counters_;
  camera::StreamLoop loop_;
  std::unique_ptr<V4l2Camera> camera_;
  std::int64_t frame_counter_ = 0;
};

}  // namespace selfcal::v4l2
