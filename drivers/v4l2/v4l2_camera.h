// A UVC depth camera with Z16 frames (RealSense and the like; Kinect v1 through gspca), through
// V4L2 mmap streaming behind the V4l2Io seam: format negotiation, buffers mapped once, buffer
// timestamps (CLOCK_MONOTONIC) mapped to host CLOCK_REALTIME. Knows nothing of LCM.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/timing/counter_unwrapper.h"
#include "core/util/expected.h"
#include "drivers/v4l2/v4l2_io.h"

namespace selfcal::v4l2 {

struct CameraOptions {
  std::string device = "/dev/video0";
  std::uint32_t width = 0, height = 0;  // 0: the device's current size
  std::uint32_t fps = 0;                // 0: the device's current rate
  std::uint32_t buffers = 4;
};

struct Format {
  std::uint32_t width = 0, height = 0, bytes_per_line = 0, fps = 0;
};

struct Frame {
  std::int64_t host_ns = 0;    // exposure time as host CLOCK_REALTIME [ns]
  std::int64_t device_ns = 0;  // the buffer's timestamp as the driver gave it
  std::uint32_t sequence = 0;
  std::uint32_t width = 0, height = 0;
};

struct Counters {
  std::uint64_t frames = 0;
  std::uint64_t dropped = 0;        // buffers flagged V4L2_BUF_FLAG_ERROR or short
  std::uint64_t sequence_gaps = 0;  // frames the driver skipped (sequence jumps)
};

class V4l2Camera {
 public:
  // `io` must outlive the camera.
  static Expected<std::unique_ptr<V4l2Camera>> Open(V4l2Io& io, const CameraOptions& options);
  ~V4l2Camera();
  V4l2Camera(const V4l2Camera&) = delete;
  V4l2Camera& operator=(const V4l2Camera&) = delete;

  // Waits up to `timeout_ms`; copies one Z16 frame into `depth` (resized on size change only).
  // False on timeout or a dropped buffer; an error when the device failed (e.g. unplugged).
  Expected<bool> NextFrame(int timeout_ms, std::vector<std::int16_t>& depth, Frame& frame);
  const Format& format() const { return format_; }
  const Counters& counters() const { return counters_; }

 private:
  explicit V4l2Camera(V4l2Io& io) : io_(io) {}
  Status Negotiate(const CameraOptions& options);
  Status StartStreaming(std::uint32_t count);

  V4l2Io& io_;
  std::string device_;
  int fd_ = -1;
  Format format_;
  struct Mapping {
    void* address = nullptr;
    std::size_t length = 0;
  };
  std::vector<Mapping> mappings_;
  bool streaming_ = false;
  // The driver's 32-bit buffer sequence: a gap is frames it skipped; it restarts at STREAMON.
  timing::CounterUnwrapper sequence_{
      timing::CounterOptions::Bits(32, timing::CounterOptions::Backwards::kRestart)};
  Counters counters_;
};

}  // namespace selfcal::v4l2
