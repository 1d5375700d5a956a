// An OpenNI2 depth camera (Kinect v1 through a freenect driver, Azure Kinect through K4ADriver,
// any OpenNI2 driver) or an .oni recording: 16-bit depth in mm, intrinsics from the stream's
// field-of-view properties or from configuration, optional recording to .oni.
// Returns selfcal types; knows nothing of LCM.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/camera/pinhole_intrinsics.h"
#include "core/util/expected.h"

namespace selfcal::openni2 {

struct CameraOptions {
  std::string uri;                     // device URI; empty: any device
  std::string oni_path;                // play this recording instead of a device
  std::string record_path;             // record the depth stream to this .oni file
  int width = 0, height = 0, fps = 0;  // 0: the device's current mode
  PinholeIntrinsics intrinsics;        // all zero: from HORIZONTAL_FOV / VERTICAL_FOV
};

struct DepthFrame {
  std::uint64_t device_timestamp_us = 0;
  std::int64_t frame_index = 0;
  int width = 0, height = 0;
  double depth_unit_m = 0.001;
};

class OpenNi2Camera {
 public:
  static Expected<std::unique_ptr<OpenNi2Camera>> Open(const CameraOptions& options);
  ~OpenNi2Camera();

  // Waits up to `timeout` for a frame and copies its depth (row-major, counts of depth_unit_m)
  // into `depth`, resized only when the size changes. Returns false on timeout and, for a
  // recording, at its end (see at_end()).
  Expected<bool> NextFrame(std::chrono::milliseconds timeout, std::vector<std::int16_t>& depth,
                           DepthFrame& frame);
  bool at_end() const { return at_end_; }
  bool playback() const { return !options_.oni_path.empty(); }
  const PinholeIntrinsics& intrinsics() const { return intrinsics_; }
  const std::string& description() const { return description_; }
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  struct Impl;
  OpenNi2Camera();
  CameraOptions options_;
  std::unique_ptr<Impl> impl_;
  PinholeIntrinsics intrinsics_;
  std::string description_;
  int width_ = 0, height_ = 0;
  int frames_in_recording_ = 0;
  int frames_read_ = 0;
  bool at_end_ = false;
};

}  // namespace selfcal::openni2
