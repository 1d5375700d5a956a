// What every camera driver (selfcal-aravis, -openni2, -v4l2) shares around its device: the channel
// it publishes on, the channel whose scan_marker_t BEGIN events request frames, when it stops and
// how it waits for a camera that went away; the subscription to those requests, and the run loop
// of the streaming cameras.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <string>
#include <vector>

#include "core/util/log.h"
#include "protocols/bus/bus.h"
#include "protocols/camera/depth_image_publisher.h"
#include "protocols/lcm/channels.h"

namespace selfcal::camera {

struct StreamOptions {
  std::string channel;  // of the published frames
  std::string trigger_channel = channels::kScanMarker;
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

// What a streaming camera driver counts.
struct StreamCounters {
  std::uint64_t published = 0;
  std::uint64_t requests = 0;
  std::uint64_t reopens = 0;  // the camera was opened again after it had been open
};

// The bookkeeping of the run loop every streaming depth camera driver (selfcal-openni2,
// selfcal-v4l2) shares around its own open / next-frame / publish calls: servicing the bus,
// another attempt to open the camera every reconnect_period while it is away (every 20th failure
// logged), the silence after which an open camera is closed, the publication of
// selfcal.depth_image_t, and in request mode the one frame published per request (the first
// exposed after it).
class StreamLoop {
 public:
  // Counts into `counters`, which the driver owns (and may extend).
  StreamLoop(const StreamOptions& options, bool request_mode, Bus& bus, LogSink log,
             StreamCounters& counters);

  // Subscribes to the requests (in request mode); once, before the loop.
  void Begin();
  // Services the bus, waiting a little while no camera is open so that the loop does not spin.
  // Errors only for a broken bus, and none once `stop` is set (the error is EINTR on SIGTERM).
  Status ServiceBus(bool camera_open, const std::atomic<bool>& stop);
  // Whether an attempt to open the camera is due; if so, the next one is a reconnect_period on.
  bool OpenDue();
  void OpenFailed(const std::string& why);
  // The camera opened: a second open counts as a reopen; its frame timeout starts now.
  void Opened();
  void FrameReceived();
  // Whether the open camera has sent no frame for frame_timeout.
  bool Silent() const;
  // Whether the frame exposed at `utime` is published: every frame, or in request mode the
  // first after the oldest pending request (which it answers).
  bool Admit(std::int64_t utime);
  // The buffer the camera fills with a frame's depth values (row-major).
  std::vector<std::int16_t>& depth() { return depth_; }
  // Publishes the frame in depth() on the stream's channel and counts it; true when max_frames
  // have been published.
  Expected<bool> Publish(const DepthImageHeader& header);

  const LogSink& log() const { return log_; }

 private:
  using Clock = std::chrono::steady_clock;

  const StreamOptions& options_;
  bool request_mode_;
  Bus& bus_;
  LogSink log_;
  Clock::time_point next_open_ = Clock::now();
  Clock::time_point last_frame_ = Clock::now();
  int failures_ = 0;
  bool opened_before_ = false;
  std::deque<std::int64_t> requests_;  // utimes of pending requests
  std::vector<std::int16_t> depth_;
  DepthImagePublisher publisher_;
  StreamCounters& counters_;
};

}  // namespace selfcal::camera
