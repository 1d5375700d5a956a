// The camera drivers' shared stream options, frame requests and depth image publication, over
// memq://.
#include "protocols/camera/camera_stream.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "protocols/camera/depth_image_publisher.h"
#include "selfcal/depth_image_t.hpp"
#include "selfcal/scan_marker_t.hpp"

namespace selfcal::camera {
namespace {

TEST(StreamOptions, DoneOnlyWithALimitReached) {
  StreamOptions options;
  EXPECT_FALSE(options.Done(0));
  EXPECT_FALSE(options.Done(1000000));
  options.max_frames = 3;
  EXPECT_FALSE(options.Done(2));
  EXPECT_TRUE(options.Done(3));
  EXPECT_TRUE(options.Done(4));
}

TEST(SubscribeScanRequests, CallsBackForEachBeginOnly) {
  auto bus = OpenLcmBus("memq://");
  ASSERT_TRUE(bus.ok()) << bus.error().message;
  std::vector<std::int64_t> requests;
  std::vector<std::string> warnings;
  SubscribeScanRequests(
      **bus, "MARKER",
      [&warnings](LogLevel level, const std::string& message) {
        if (level == LogLevel::kWarning) warnings.push_back(message);
      },
      [&requests](std::int64_t utime) { requests.push_back(utime); });

  selfcal::scan_marker_t marker;
  marker.utime = 100;
  marker.event = selfcal::scan_marker_t::BEGIN;
  ASSERT_TRUE((*bus)->Publish("MARKER", marker).ok());
  marker.utime = 200;
  marker.event = selfcal::scan_marker_t::END;
  ASSERT_TRUE((*bus)->Publish("MARKER", marker).ok());
  marker.utime = 300;
  marker.event = selfcal::scan_marker_t::BEGIN;
  ASSERT_TRUE((*bus)->Publish("MARKER", marker).ok());
  ASSERT_TRUE((*bus)->Publish("OTHER", marker).ok());
  const std::vector<std::uint8_t> garbage = {1, 2, 3};
  ASSERT_TRUE((*bus)->Publish("MARKER", std::span<const std::uint8_t>(garbage)).ok());
  while (true) {
    auto handled = (*bus)->HandleOnce(std::chrono::milliseconds(0));
    ASSERT_TRUE(handled.ok());
    if (!*handled) break;
  }

  EXPECT_EQ(requests, (std::vector<std::int64_t>{100, 300}));
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("ignoring trigger message"), std::string::npos);
}

TEST(DepthImagePublisher, PublishesHeaderAndPixelsAndKeepsThePixels) {
  auto bus = OpenLcmBus("memq://");
  ASSERT_TRUE(bus.ok()) << bus.error().message;
  std::vector<selfcal::depth_image_t> images;
  (*bus)->Subscribe("DEPTH", [&images](const BusMessage& m) {
    auto image = DecodeLcm<selfcal::depth_image_t>(m.data, m.channel);
    ASSERT_TRUE(image.ok()) << image.error().message;
    images.push_back(std::move(*image));
  });
  DepthImagePublisher publisher;
  std::vector<std::int16_t> depth = {1, 2, 3, 4, 5, 6};
  const DepthImageHeader header{.utime = 1000,
                                .device_utime = 900,
                                .frame_counter = 7,
                                .width = 3,
                                .height = 2,
                                .depth_unit_m = 0.0005,
                                .intrinsics = {50.0, 51.0, 1.5, 0.5}};
  for (int i = 0; i < 2; ++i) ASSERT_TRUE(publisher.Publish(**bus, "DEPTH", header, depth).ok());
  EXPECT_EQ(depth, (std::vector<std::int16_t>{1, 2, 3, 4, 5, 6}));
  while (true) {
    auto handled = (*bus)->HandleOnce(std::chrono::milliseconds(0));
    ASSERT_TRUE(handled.ok());
    if (!*handled) break;
  }
  ASSERT_EQ(images.size(), 2u);
  for (const auto& image : images) {
    EXPECT_EQ(image.utime, 1000);
    EXPECT_EQ(image.device_utime, 900);
    EXPECT_EQ(image.frame_counter, 7);
    EXPECT_EQ(image.width, 3);
    EXPECT_EQ(image.height, 2);
    EXPECT_EQ(image.depth_unit_m, 0.0005);
    EXPECT_EQ(image.fx, 50.0);
    EXPECT_EQ(image.fy, 51.0);
    EXPECT_EQ(image.cx, 1.5);
    EXPECT_EQ(image.cy, 0.5);
    EXPECT_EQ(image.num_pixels, 6);
    EXPECT_EQ(image.depth, depth);
  }
}

}  // namespace
}  // namespace selfcal::camera
