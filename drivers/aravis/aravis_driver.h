// The selfcal-aravis process: an AravisCamera, reconnection, trigger requests from LCM and
// publication of selfcal.organized_cloud_t. Buffers are allocated once per connection.
//
// Trigger requests (software trigger mode): every selfcal.scan_marker_t with event BEGIN on the
// trigger channel (default SELFCAL_SCAN_MARKER, published by the daemon when the arm stands still
// at a scan pose) asks for exactly one frame. The frame's utime is its exposure time (after the
// marker); the daemon waits for it before it publishes END. A request made while the camera is
// away waits for the reconnection; a triggered frame lost to missing packets is triggered again
// (up to `retriggers` times), so each request yields one published frame or a logged failure.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "core/timing/clock_filter.h"
#include "core/timing/counter_unwrapper.h"
#include "core/util/log.h"
#include "drivers/aravis/aravis_camera.h"
#include "protocols/bus/bus.h"
#include "protocols/camera/camera_stream.h"
#include "protocols/camera/frame_clock.h"
#include "protocols/lcm/channels.h"
#include "selfcal/organized_cloud_t.hpp"

namespace selfcal::aravis {

struct DriverOptions {
  CameraOptions camera;
  // frame_timeout: for a triggered frame, or free-run silence.
  camera::StreamOptions stream{.channel = channels::kOrganizedCloud,
                               .reconnect_period = std::chrono::milliseconds(500)};
  int retriggers = 2;
};

struct DriverCounters {
  std::uint64_t published = 0;
  std::uint64_t requests = 0;
  std::uint64_t failed_requests = 0;
  std::uint64_t reconnects = 0;
  std::uint64_t dropped = 0;  // incomplete + corrupted buffers, summed over connections
  std::uint64_t stray = 0;    // frames that arrived without a request in trigger mode
};

class AravisDriver {
 public:
  AravisDriver(DriverOptions options, Bus& bus, LogSink logger);
  // Runs until `stop` is set or max_frames were published. Errors only for a broken bus.
  Status Run(const std::atomic<bool>& stop);
  const DriverCounters& counters() const { return counters_; }

 private:
  bool Connect();
  void Disconnect(const std::string& why);
  Status Publish(const FrameInfo& info);

  DriverOptions options_;
  Bus& bus_;
  LogSink log_;
  std::unique_ptr<AravisCamera> camera_;
  CloudStorage storage_;
  selfcal::organized_cloud_t message_;
  std::vector<std::uint8_t> encoded_;
  timing::ClockFilter clock_{camera::FrameClockOptions()};
  DriverCounters counters_;
  std::uint64_t dropped_before_ = 0;  // camera counters of the current connection already summed
  std::int64_t pending_requests_ = 0;
  bool trigger_outstanding_ = false;
  int connect_failures_ = 0;
  std::chrono::steady_clock::time_point deadline_;
  // GigE Vision 1 block ids are 16 bits and skip 0: unwrapped into a counter whose gaps are
  // losses and which goes on across reconnections.
  timing::CounterUnwrapper block_ids_{{.modulus = 0xFFFF, .first_value = 1}};
  std::int64_t frame_counter_ = 0;
};

}  // namespace selfcal::aravis
