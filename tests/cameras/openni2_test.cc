// selfcal-openni2 with the real libOpenNI2 loading our simulated-camera plugin from a private
// driver folder (OPENNI2_ROOT), LCM over udpm inside the network namespace ctest made.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "core/camera/pinhole_intrinsics.h"
#include "selfcal/depth_image_t.hpp"
#include "selfcal/scan_marker_t.hpp"
#include "tests/cameras/camera_test_util.h"
#include "tools/sim_cameras/scenario_camera.h"

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

std::string ScenarioUri(const std::string& relative) {
  return "selfcal-sim://depth?scenario=" + std::string(SELFCAL_SOURCE_DIR_PATH) + "/" + relative +
         "&view=0";
}

// The plugin's intrinsics for a scenario's sensor, computed as the plugin does (through the field
// of view it reports; the driver's, from the float property, agree within 1e-4 px).
PinholeIntrinsics PluginIntrinsics(const sim::SensorModel& s) {
  const double hfov_deg = 2 * std::atan(s.width / 2.0 / s.intrinsics.fx) / kDegree;
  const double vfov_deg = 2 * std::atan(s.height / 2.0 / s.intrinsics.fy) / kDegree;
  return PinholeIntrinsics::FromFieldOfView(s.width, s.height, hfov_deg * kDegree,
                                            vfov_deg * kDegree);
}

std::unique_ptr<sim_cameras::ScenarioCamera> ScenarioCamera(const std::string& relative) {
  auto camera =
      sim_cameras::ScenarioCamera::Create(std::string(SELFCAL_SOURCE_DIR_PATH) + "/" + relative, 0);
  EXPECT_TRUE(camera.ok()) << camera.error().message;
  return camera.ok() ? std::move(*camera) : nullptr;
}

// The field twin of kinect-bunny through libOpenNI2 and the driver: frames of the camera at the
// plan's first view differ from the ideal ray casts as the scenario's effects say. Bias on every
// surface: 3 mm + 0.1 % of the depth (range bias; its 2 mm warm-up has decayed on the device
// clock, which started an hour before) and 2 mm + 0.2 % (intrinsics); noise of the sensor file,
// 2.53 mm + 0.21 % of the depth, grown by 1 / cos of the incidence; flying pixels at the bunny's
// silhouette, between it and the table.
TEST_F(OpenNi2DriverTest, ScenarioFieldFramesShowItsEffects) {
  auto camera = ScenarioCamera("config/scenarios/field/kinect-bunny.yaml");
  ASSERT_TRUE(camera);
  ASSERT_TRUE(camera->field());
  Images images(*bus_, kChannel);
  auto driver = Driver({"--uri", ScenarioUri("config/scenarios/field/kinect-bunny.yaml")});
  ASSERT_TRUE(images.WaitFor(3, 20s)) << driver->Stderr();
  const auto& a = images.messages[1];
  const auto& b = images.messages[2];
  ASSERT_EQ(a.width, 320);
  ASSERT_EQ(a.height, 288);
  EXPECT_NEAR(a.fx, 208.5, 1e-3);  // the sensor file's intrinsics, through the field of view
  EXPECT_NEAR(a.fy, 226.0, 1e-3);
  const PinholeIntrinsics k = PluginIntrinsics(camera->sensor());
  const std::vector<float> ideal = camera->IdealDepth(320, 288, k);
  const int w = 320, h = 288;
  const auto at = [&](int u, int v) { return ideal[static_cast<std::size_t>(v * w + u)]; };
  const auto mm = [](const selfcal::depth_image_t& image, std::size_t i) {
    return static_cast<std::uint16_t>(image.depth[i]) * 0.001;
  };
  std::vector<double> biases;
  double squares = 0, expected_squares = 0;
  int edges = 0, flying = 0;
  for (int v = 1; v + 1 < h; ++v) {
    for (int u = 1; u + 1 < w; ++u) {
      const std::size_t i = static_cast<std::size_t>(v * w + u);
      const double z = at(u, v);
      if (!(z > 0) || mm(a, i) == 0 || mm(b, i) == 0) continue;
      const double neighbours[4] = {at(u - 1, v), at(u + 1, v), at(u, v - 1), at(u, v + 1)};
      double jump = 0, far = 0;
      for (double n : neighbours) {
        jump = std::max(jump, n > 0 ? std::abs(n - z) : 1.0);
        if (n > z) far = std::max(far, n);
      }
      const double sigma = 0.00253 + 0.0021 * z;
      if (jump < 0.005) {
        biases.push_back(mm(a, i) - z);
        const double d = mm(a, i) - mm(b, i);
        squares += d * d / 2;
        expected_squares += sigma * sigma;
      } else if (jump > 0.1 && far > 0) {
        // The near side of a silhouette: a flying pixel lies well between near and far.
        ++edges;
        if (mm(a, i) > z + 0.02 && mm(a, i) < far - 0.02) ++flying;
      }
    }
  }
  ASSERT_GT(biases.size(), 10000u);
  std::nth_element(biases.begin(), biases.begin() + static_cast<long>(biases.size() / 2),
                   biases.end());
  const double median_bias = biases[biases.size() / 2];
  const double noise_ratio = std::sqrt(squares / expected_squares);
  std::printf(
      "field frame: bias %.2f mm, noise %.2f x the sensor file's over %zu smooth pixels; "
      "%d of %d silhouette pixels flying\n",
      1e3 * median_bias, noise_ratio, biases.size(), flying, edges);
  const double depth = 0.65;  // about the view's distance
  EXPECT_NEAR(median_bias, 0.003 + 0.001 * depth + 0.002 + 0.002 * depth, 0.0015);
  EXPECT_GT(noise_ratio, 1.0);  // 1 / cos i >= 1
  EXPECT_LT(noise_ratio, 2.5);
  EXPECT_GT(edges, 50);
  EXPECT_GT(flying, edges / 10);
}

// Without effects a scenario's camera serves the ideal ray casts plus the plugin's own noise
// (noise_m, 2.5 mm), as the analytic scene does.
TEST_F(OpenNi2DriverTest, ScenarioWithoutEffectsServesTheIdealRayCasts) {
  auto camera = ScenarioCamera("config/scenarios/kinect-bunny.yaml");
  ASSERT_TRUE(camera);
  ASSERT_FALSE(camera->field());
  Images images(*bus_, kChannel);
  auto driver = Driver({"--uri", ScenarioUri("config/scenarios/kinect-bunny.yaml")});
  ASSERT_TRUE(images.WaitFor(2, 20s)) << driver->Stderr();
  const auto& image = images.messages.back();
  const std::vector<float> ideal = camera->IdealDepth(320, 288, PluginIntrinsics(camera->sensor()));
  int valid = 0;
  double squares = 0;
  for (std::size_t i = 0; i < ideal.size(); ++i) {
    const auto raw = static_cast<std::uint16_t>(image.depth[i]);
    if (!(ideal[i] > 0)) {
      EXPECT_EQ(raw, 0) << "pixel " << i;
      continue;
    }
    ASSERT_NE(raw, 0) << "pixel " << i;
    const double error = raw * 0.001 - ideal[i];
    EXPECT_LT(std::abs(error), 6 * 0.0025 + 0.0005) << "pixel " << i;
    squares += error * error;
    ++valid;
  }
  EXPECT_GT(valid, 15000);
  EXPECT_NEAR(std::sqrt(squares / valid), 0.0025, 0.0005);
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
