// What every camera driver (selfcal-aravis, -openni2, -v4l2) shares around its device: the channel
// it publishes on, the channel whose scan_marker_t BEGIN events request frames, when it stops and
// how it waits for a camera that went away; and the subscription to those requests.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>

#include "core/util/log.h"
#include "protocols/bus/bus.h"

namespace selfcal::camera {

struct StreamOptions {
  std::string channel;  // of the published frames
  std::string trigger_channel = "SELFCAL_SCAN_MARKER";
  std::int64_t max_frames = 0;  // stop after this many published frames (0: run until stopped)
  std::chrono::milliseconds reconnect_period{1000};
  std::chrono::milliseconds frame_timeout{2000};  // silence after which the camera is reopened

  // Whether `published` frames are all that were asked for.
  bool Done(std::uint64_t published) const {
    return max_frames > 0 && static_cast<std::int64_t>(published) >= max_frames;
  }
};

// Subscribes to `channel` and calls `on_request(utime)` for every selfcal.scan_marker_t whose event
// is BEGIN; other events are ignored, undecodable messages logged and dropped.
void SubscribeScanRequests(Bus& bus, const std::string& channel, LogSink log,
                           std::function<void(std::int64_t utime)> on_request);

}  // namespace selfcal::camera
