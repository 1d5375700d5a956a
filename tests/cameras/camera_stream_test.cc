// The camera drivers' shared stream options and frame requests, over memq://.
#include "protocols/camera/camera_stream.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

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

}  // namespace
}  // namespace selfcal::camera
