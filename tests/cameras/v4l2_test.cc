// selfcal-v4l2's camera and driver through the seam, against a fake Z16 device
// (fake_v4l2_device.h).
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "drivers/v4l2/v4l2_driver.h"
#include "protocols/lcm_log/lcm_codec.h"
#include "selfcal/depth_image_t.hpp"
#include "selfcal/scan_marker_t.hpp"
#include "tests/cameras/fake_v4l2_device.h"

namespace selfcal {
namespace {

using testing::FakeZ16Device;

std::int64_t RealtimeNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

TEST(V4l2Camera, NegotiatesZ16AndStreamsFramesWithRealtimeStamps) {
  FakeZ16Device device({});
  auto camera = v4l2::V4l2Camera::Open(device, {"/dev/video9", 80, 60, 30, 4});
  ASSERT_TRUE(camera.ok()) << camera.error().message;
  EXPECT_EQ((*camera)->format().width, 80u);
  EXPECT_EQ((*camera)->format().height, 60u);
  EXPECT_EQ((*camera)->format().fps, 30u);
  std::vector<std::int16_t> depth;
  for (std::uint32_t k = 0; k < 10; ++k) {
    v4l2::Frame frame;
    auto got = (*camera)->NextFrame(100, depth, frame);
    ASSERT_TRUE(got.ok() && *got);
    EXPECT_EQ(frame.sequence, k);
    ASSERT_EQ(depth.size(), 80u * 60u);
    EXPECT_EQ(depth[0], FakeZ16Device::Depth(0, 0, k));
    EXPECT_EQ(depth[59 * 80 + 79], FakeZ16Device::Depth(79, 59, k));
    // CLOCK_MONOTONIC buffer time, mapped to CLOCK_REALTIME.
    EXPECT_LT(std::abs(RealtimeNs() - frame.host_ns), 50'000'000);
  }
  EXPECT_EQ(device.maps, 4);
  camera->reset();
  EXPECT_EQ(device.unmaps, 4);
  EXPECT_EQ(device.streamoffs, 1);
  EXPECT_EQ(device.closes, 1);
}

TEST(V4l2Camera, TakesTheSizeTheDriverAdjustedAndSkipsLinePadding) {
  FakeZ16Device::Config config;
  config.max_width = 64;  // asks for 80, gets 64
  config.padding_bytes = 32;
  FakeZ16Device device(config);
  auto camera = v4l2::V4l2Camera::Open(device, {"/dev/video9", 80, 48, 0, 3});
  ASSERT_TRUE(camera.ok()) << camera.error().message;
  EXPECT_EQ((*camera)->format().width, 64u);
  EXPECT_EQ((*camera)->format().bytes_per_line, 160u);
  std::vector<std::int16_t> depth;
  v4l2::Frame frame;
  ASSERT_TRUE(*(*camera)->NextFrame(100, depth, frame));
  ASSERT_EQ(depth.size(), 64u * 48u);
  for (std::uint32_t v = 0; v < 48; ++v) {
    for (std::uint32_t u = 0; u < 64; ++u)
      ASSERT_EQ(depth[v * 64 + u], FakeZ16Device::Depth(u, v, 0));
  }
}

TEST(V4l2Camera, DeviceWithoutZ16IsAnErrorNamingWhatItOffers) {
  FakeZ16Device::Config config;
  config.formats = {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_MJPEG};
  FakeZ16Device device(config);
  auto camera = v4l2::V4l2Camera::Open(device, {"/dev/video9", 0, 0, 0, 4});
  ASSERT_FALSE(camera.ok());
  EXPECT_NE(
      camera.error().message.find("/dev/video9: offers no Z16 depth format (offers: YUYV, MJPG)"),
      std::string::npos)
      << camera.error().message;
  EXPECT_EQ(device.closes, 1);
}

TEST(V4l2Camera, ErrorBuffersAreDroppedAndSequenceGapsCounted) {
  FakeZ16Device::Config config;
  config.error_frames = {2};
  config.skipped_frames = {5, 6};
  FakeZ16Device device(config);
  auto camera = v4l2::V4l2Camera::Open(device, {"/dev/video9", 0, 0, 0, 4});
  ASSERT_TRUE(camera.ok()) << camera.error().message;
  std::vector<std::int16_t> depth;
  std::vector<std::uint32_t> sequences;
  for (int k = 0; k < 8; ++k) {
    v4l2::Frame frame;
    auto got = (*camera)->NextFrame(100, depth, frame);
    ASSERT_TRUE(got.ok());
    if (*got) sequences.push_back(frame.sequence);
  }
  EXPECT_EQ(sequences, (std::vector<std::uint32_t>{0, 1, 3, 4, 7, 8, 9}));
  EXPECT_EQ((*camera)->counters().dropped, 1u);
  EXPECT_EQ((*camera)->counters().sequence_gaps, 3u);  // frame 2 (error) and frames 5, 6 (lost)
}

TEST(V4l2Camera, MissingDeviceIsAnError) {
  FakeZ16Device device({});
  device.present = false;
  auto camera = v4l2::V4l2Camera::Open(device, {"/dev/video9", 0, 0, 0, 4});
  ASSERT_FALSE(camera.ok());
  EXPECT_NE(camera.error().message.find("cannot open /dev/video9"), std::string::npos);
}

// Stops a driver run that would otherwise wait for ever, and is joined before the test ends.
class Deadline {
 public:
  explicit Deadline(std::chrono::milliseconds limit)
      : thread_([this, limit] {
          const auto end = std::chrono::steady_clock::now() + limit;
          while (!done_ && std::chrono::steady_clock::now() < end) {
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
          }
          stop = true;
        }) {}
  ~Deadline() {
    done_ = true;
    thread_.join();
  }
  std::atomic<bool> stop{false};

 private:
  std::atomic<bool> done_{false};
  std::thread thread_;
};

class V4l2DriverTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto bus = OpenLcmBus("memq://");
    ASSERT_TRUE(bus.ok());
    bus_ = std::move(*bus);
    bus_->Subscribe("DEPTH", [this](const BusMessage& m) {
      auto image = DecodeLcm<selfcal::depth_image_t>(m.data, m.channel);
      ASSERT_TRUE(image.ok()) << image.error().message;
      images_.push_back(std::move(*image));
    });
  }
  v4l2::DriverOptions Options() {
    v4l2::DriverOptions options;
    options.camera = {"/dev/video9", 0, 0, 0, 4};
    options.intrinsics = {50.0, 51.0, 31.5, 23.5};
    options.stream.channel = "DEPTH";
    options.stream.trigger_channel = "MARKER";
    options.stream.reconnect_period = std::chrono::milliseconds(10);
    return options;
  }
  void Drain() {
    while (true) {
      auto handled = bus_->HandleOnce(std::chrono::milliseconds(0));
      if (!handled.ok() || !*handled) break;
    }
  }
  std::unique_ptr<Bus> bus_;
  std::vector<selfcal::depth_image_t> images_;
  std::vector<std::string> log_;
};

TEST_F(V4l2DriverTest, PublishesDepthImagesAndReopensAnUnpluggedDevice) {
  FakeZ16Device::Config config;
  config.unplug_after_frames = 3;
  FakeZ16Device device(config);
  auto options = Options();
  options.stream.max_frames = 6;
  v4l2::V4l2Driver driver(options, device, *bus_, [&](selfcal::LogLevel, const std::string& m) {
    log_.push_back(m);
    // The device comes back after it was unplugged.
    if (m.find("reopening") != std::string::npos) device.present = true;
  });
  Deadline deadline(std::chrono::seconds(10));
  ASSERT_TRUE(driver.Run(deadline.stop).ok());
  Drain();
  ASSERT_EQ(images_.size(), 6u);
  EXPECT_EQ(driver.counters().reopens, 1u);
  EXPECT_EQ(device.opens, 2);
  EXPECT_EQ(device.maps, device.unmaps + 4) << "the first connection's buffers are unmapped";
  const auto& image = images_.back();
  EXPECT_EQ(image.width, 64);
  EXPECT_EQ(image.height, 48);
  EXPECT_EQ(image.fx, 50.0);
  EXPECT_EQ(image.cy, 23.5);
  EXPECT_EQ(image.depth_unit_m, 0.001);
  EXPECT_EQ(image.depth[10 * 64 + 5], FakeZ16Device::Depth(5, 10, 5));
  for (std::size_t i = 1; i < images_.size(); ++i) {
    EXPECT_EQ(images_[i].frame_counter, images_[i - 1].frame_counter + 1);
    EXPECT_GE(images_[i].utime, images_[i - 1].utime);
  }
}

TEST_F(V4l2DriverTest, RequestModePublishesOneFramePerRequest) {
  FakeZ16Device device({});
  auto options = Options();
  options.request_mode = true;
  options.stream.max_frames = 2;
  selfcal::scan_marker_t marker;
  // memq drops messages nobody subscribed to: publish once the driver runs (it logs "opened").
  v4l2::V4l2Driver driver(options, device, *bus_, [&](selfcal::LogLevel, const std::string& m) {
    log_.push_back(m);
    if (m.rfind("opened", 0) != 0) return;
    marker.utime = RealtimeNs() / 1000;
    marker.event = selfcal::scan_marker_t::BEGIN;
    ASSERT_TRUE(bus_->Publish("MARKER", marker).ok());
    marker.event = selfcal::scan_marker_t::END;
    ASSERT_TRUE(bus_->Publish("MARKER", marker).ok());
    marker.event = selfcal::scan_marker_t::BEGIN;
    marker.utime += 1;
    ASSERT_TRUE(bus_->Publish("MARKER", marker).ok());
  });
  Deadline deadline(std::chrono::seconds(10));
  ASSERT_TRUE(driver.Run(deadline.stop).ok());
  EXPECT_FALSE(deadline.stop.load()) << "the driver should stop after two frames";
  Drain();
  ASSERT_EQ(images_.size(), 2u);
  EXPECT_EQ(driver.counters().requests, 2u);
  EXPECT_GT(images_[0].utime, marker.utime - 1);
}

}  // namespace
}  // namespace selfcal
