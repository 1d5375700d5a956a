// selfcal-openni2 with the real libOpenNI2 loading our simulated-camera plugin from a private
// driver folder (OPENNI2_ROOT), LCM over udpm inside the network namespace ctest made.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "core/camera/pinhole_intrinsics.h"
#include "selfcal/depth_image_t.hpp"
#include "selfcal/scan_marker_t.hpp"
#include "tests/cameras/camera_test_util.h"

namespace selfcal {
namespace {

using namespace std::chrono_literals;
using testing::Child;
using Images = testing::Listener<selfcal::depth_image_t>;

constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
constexpr const char* kChannel = "TEST_DEPTH";
constexpr const char* kMarkers = "TEST_MARKER";
constexpr const char* kUri =
    "selfcal-sim://depth?width=160&height=120&fps=30&hfov_deg=75&vfov_deg=65";
constexpr double kDegree = 3.14159265358979323846 / 180.0;

class OpenNi2DriverTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // libOpenNI2 finds its drivers beside itself: run the driver on the private copy.
    ::setenv("LD_LIBRARY_PATH", OPENNI2_ROOT, 1);
    auto bus = OpenLcmBus(kUrl);
    ASSERT_TRUE(bus.ok()) << bus.error().message << " (run inside tests/netns-run)";
    bus_ = std::move(*bus);
  }
  std::unique_ptr<Child> Driver(std::vector<std::string> extra) {
    std::vector<std::string> args = {
        SELFCAL_OPENNI2_BINARY, "--lcm-url", kUrl, "--channel", kChannel,
        "--trigger-channel",    kMarkers};
    args.insert(args.end(), extra.begin(), extra.end());
    return std::make_unique<Child>(
        args, testing::TempPath("openni2-" + std::to_string(++count_) + ".log"));
  }
  std::unique_ptr<Bus> bus_;
  int count_ = 0;
};

// The plugin's scene (tools/sim_cameras/openni2_plugin.cc), computed here independently.
double TruthDepth(double a, double b) {
  const double bx = 0.1, by = -0.05, bz = 1.1, r = 0.2;
  const double qa = a * a + b * b + 1, qb = a * bx + b * by + bz,
               qc = bx * bx + by * by + bz * bz - r * r;
  double t = qb * qb - qa * qc >= 0 ? (qb - std::sqrt(qb * qb - qa * qc)) / qa : 0.0;
  if (t <= 0) t = 1.6 / (1 - 0.5 * b);
  return (t >= 0.5 && t <= 2.0) ? t : 0.0;
}

TEST_F(OpenNi2DriverTest, LiveDepthHasFovIntrinsicsHostTimesAndMatchesTheScene) {
  Images images(*bus_, kChannel);
  auto driver = Driver({"--uri", kUri});
  ASSERT_TRUE(images.WaitFor(10, 10s)) << driver->Stderr();
  const auto& image = images.messages.back();
  ASSERT_EQ(image.width, 160);
  ASSERT_EQ(image.height, 120);
  EXPECT_EQ(image.depth_unit_m, 0.001);
  EXPECT_NEAR(image.fx, 80.0 / std::tan(37.5 * kDegree), 1e-3);  // from HORIZONTAL_FOV
  EXPECT_NEAR(image.fy, 60.0 / std::tan(32.5 * kDegree), 1e-3);
  EXPECT_NEAR(image.cx, 79.5, 1e-9);
  EXPECT_NEAR(image.cy, 59.5, 1e-9);
  // The plugin's device clock started an hour before: utime must be host time nonetheless.
  EXPECT_LT(std::abs(testing::NowUtime() - image.utime), 200'000);
  EXPECT_GT(image.device_utime, 3'600'000'000LL);
  for (std::size_t i = 1; i < images.messages.size(); ++i) {
    EXPECT_EQ(images.messages[i].frame_counter, images.messages[i - 1].frame_counter + 1);
    const auto dt = images.messages[i].utime - images.messages[i - 1].utime;
    EXPECT_NEAR(static_cast<double>(dt), 33'333.0, 10'000.0);
  }
  int valid = 0;
  const PinholeIntrinsics k{image.fx, image.fy, image.cx, image.cy};
  for (int v = 0; v < image.height; ++v) {
    for (int u = 0; u < image.width; ++u) {
      const Eigen::Vector3d ray = k.Unproject(u, v, 1.0);
      const double truth = TruthDepth(ray.x(), ray.y());
      const auto raw =
          static_cast<std::uint16_t>(image.depth[static_cast<std::size_t>(v * image.width + u)]);
      if (truth == 0.0 || std::abs(truth - 2.0) < 0.02 || std::abs(truth - 0.5) < 0.02) continue;
      ASSERT_NE(raw, 0) << u << "," << v;
      ++valid;
      EXPECT_NEAR(raw * 0.001, truth, 6 * 0.0025 + 0.0005) << u << "," << v;
    }
  }
  EXPECT_GT(valid, 15000);
}

TEST_F(OpenNi2DriverTest, RecordsToOniAndPlaysBackTheSameFrames) {
  const std::string oni = testing::TempPath("record.oni");
  Images live(*bus_, kChannel);
  {
    auto recorder = Driver({"--uri", kUri, "--record", oni, "--max-frames", "12"});
    ASSERT_TRUE(live.WaitFor(12, 10s)) << recorder->Stderr();
    const auto end = std::chrono::steady_clock::now() + 5s;
    while (!recorder->exited() && std::chrono::steady_clock::now() < end)
      std::this_thread::sleep_for(10ms);
    ASSERT_TRUE(recorder->exited());
  }
  Images played(*bus_, kChannel);
  auto player = Driver({"--oni", oni});
  const auto end = std::chrono::steady_clock::now() + 10s;
  while (!player->exited() && std::chrono::steady_clock::now() < end) played.Spin(20ms);
  played.Spin(200ms);
  ASSERT_TRUE(player->exited()) << "playback must end at the end of the recording";
  // The recorder attaches after the stream starts, so it may miss the first live frames.
  ASSERT_GE(played.messages.size(), 8u) << player->Stderr();
  EXPECT_LE(played.messages.size(), 12u);
  EXPECT_GT(player->Counter("published"), 7);
  for (const auto& frame : played.messages) {
    const selfcal::depth_image_t* original = nullptr;
    for (const auto& l : live.messages) {
      if (l.device_utime == frame.device_utime) original = &l;
    }
    ASSERT_NE(original, nullptr) << "played frame with device time " << frame.device_utime
                                 << " was never live";
    EXPECT_EQ(frame.depth, original->depth);
    EXPECT_EQ(frame.fx, original->fx);
  }
  for (std::size_t i = 1; i < played.messages.size(); ++i) {
    EXPECT_EQ(played.messages[i].utime - played.messages[i - 1].utime,
              played.messages[i].device_utime - played.messages[i - 1].device_utime);
  }
}

TEST_F(OpenNi2DriverTest, RequestModePublishesOneFramePerRequest) {
  Images images(*bus_, kChannel);
  auto driver = Driver({"--uri", kUri, "--trigger", "request"});
  ASSERT_TRUE(driver->WaitForLog("opened", 10s)) << driver->Stderr();
  images.Spin(300ms);
  EXPECT_TRUE(images.messages.empty());
  for (int k = 0; k < 3; ++k) {
    selfcal::scan_marker_t marker;
    marker.utime = testing::NowUtime();
    marker.event = k == 1 ? selfcal::scan_marker_t::END : selfcal::scan_marker_t::BEGIN;
    marker.purpose = selfcal::scan_marker_t::FIT;
    ASSERT_TRUE(bus_->Publish(kMarkers, marker).ok());
    images.Spin(300ms);
    if (marker.event == selfcal::scan_marker_t::BEGIN) {
      ASSERT_FALSE(images.messages.empty());
      EXPECT_GT(images.messages.back().utime, marker.utime);
    }
  }
  images.Spin(300ms);
  EXPECT_EQ(images.messages.size(), 2u);
}

TEST_F(OpenNi2DriverTest, BadRecordingIsAnError) {
  const std::string path = testing::TempPath("bad.oni");
  std::ofstream(path) << "not an oni file";
  auto player = Driver({"--oni", path});
  const auto end = std::chrono::steady_clock::now() + 10s;
  while (!player->exited() && std::chrono::steady_clock::now() < end)
    std::this_thread::sleep_for(10ms);
  EXPECT_EQ(player->Stop(), 1);
  EXPECT_NE(player->Stderr().find("error: cannot open recording"), std::string::npos)
      << player->Stderr();
}

}  // namespace
}  // namespace selfcal
