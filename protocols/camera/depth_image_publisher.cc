#include "protocols/camera/depth_image_publisher.h"

#include <utility>

#include "protocols/lcm_log/lcm_codec.h"

namespace selfcal::camera {

Status DepthImagePublisher::Publish(Bus& bus, const std::string& channel,
                                    const DepthImageHeader& header,
                                    std::vector<std::int16_t>& depth) {
  message_.utime = header.utime;
  message_.device_utime = header.device_utime;
  message_.frame_counter = header.frame_counter;
  message_.width = header.width;
  message_.height = header.height;
  message_.depth_unit_m = header.depth_unit_m;
  message_.fx = header.intrinsics.fx;
  message_.fy = header.intrinsics.fy;
  message_.cx = header.intrinsics.cx;
  message_.cy = header.intrinsics.cy;
  std::swap(message_.depth, depth);  // no copy: the storage goes back after encoding
  message_.num_pixels = static_cast<std::int32_t>(message_.depth.size());
  const auto bytes = EncodeLcmInto(message_, encoded_);
  std::swap(message_.depth, depth);
  return bus.Publish(channel, bytes);
}

}  // namespace selfcal::camera
