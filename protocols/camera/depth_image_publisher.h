// Publication of selfcal.depth_image_t by the streaming depth cameras (selfcal-openni2,
// selfcal-v4l2): the message and its encoding buffer are allocated once, and the depth pixels are
// lent to the message instead of copied.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/camera/pinhole_intrinsics.h"
#include "protocols/bus/bus.h"
#include "selfcal/depth_image_t.hpp"

namespace selfcal::camera {

// Everything of a depth image but its pixels.
struct DepthImageHeader {
  std::int64_t utime = 0;         // exposure, host clock [us]
  std::int64_t device_utime = 0;  // exposure, camera clock [us]
  std::int64_t frame_counter = 0;
  std::int32_t width = 0;
  std::int32_t height = 0;
  double depth_unit_m = 0.001;  // metres per depth count
  PinholeIntrinsics intrinsics;
};

class DepthImagePublisher {
 public:
  // Publishes `depth` (row-major, header.width x header.height) on `channel`; `depth` holds the
  // same pixels again on return.
  Status Publish(Bus& bus, const std::string& channel, const DepthImageHeader& header,
                 std::vector<std::int16_t>& depth);

 private:
  selfcal::depth_image_t message_;
  std::vector<std::uint8_t> encoded_;
};

}  // namespace selfcal::camera
