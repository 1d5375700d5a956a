// The receive loop and the publisher over real LCM (memq://): what subscribers get.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <mutex>
#include <thread>

#include "drivers/wenglor/driver_loop.h"
#include "drivers/wenglor/profile_publisher.h"
#include "protocols/bus/bus.h"
#include "protocols/lcm/channels.h"
#include "selfcal/line_profile_t.hpp"
#include "tests/wenglor/sim_fixture.h"
#include "tools/sim_wenglor/scene.h"

namespace selfcal::wenglor {
namespace {

TEST(LineProfileConversion, EveryFieldLandsInItsPlace) {
  Profile profile;
  profile.Allocate(4);
  profile.num_points = 3;
  profile.utime = 111;
  profile.device_utime = 222;
  profile.counter = 333;
  profile.x = {0.1F, NAN, 0.3F, 9.0F};
  profile.z = {0.4F, NAN, 0.6F, 9.0F};
  profile.intensity = {7, 0, 9, 9};
  selfcal::line_profile_t message;
  ToLineProfile(profile, message);
  EXPECT_EQ(message.utime, 111);
  EXPECT_EQ(message.device_utime, 222);
  EXPECT_EQ(message.device_counter, 333);
  EXPECT_EQ(message.num_points, 3);
  ASSERT_EQ(message.x.size(), 3u);
  EXPECT_FLOAT_EQ(message.x[2], 0.3F);
  EXPECT_TRUE(std::isnan(message.z[1]));
  EXPECT_FLOAT_EQ(message.z[2], 0.6F);
  EXPECT_FLOAT_EQ(message.intensity[2], 9.0F);
  // The message must encode and decode with its length field matching the arrays.
  auto decoded = DecodeLcm<selfcal::line_profile_t>(EncodeLcm(message), "test");
  ASSERT_TRUE(decoded.ok()) << decoded.error().message;
  EXPECT_EQ(decoded->x.size(), 3u);
}

using testing::SimWenglorTest;

TEST_F(SimWenglorTest, ProfilesArriveOverLcmInOrderAndMatchTheTruth) {
  auto bus = OpenLcmBus("memq://");
  ASSERT_TRUE(bus.ok()) << bus.error().message;
  std::mutex mutex;
  std::vector<selfcal::line_profile_t> received;
  std::vector<std::string> decode_errors;
  (*bus)->Subscribe(channels::kLineProfile, [&](const BusMessage& message) {
    auto decoded = DecodeLcm<selfcal::line_profile_t>(message.data, message.channel);
    std::lock_guard<std::mutex> lock(mutex);
    if (decoded.ok()) {
      received.push_back(std::move(*decoded));
    } else {
      decode_errors.push_back(decoded.error().message);
    }
  });
  auto scanner = MakeScanner(Config());
  ASSERT_TRUE(scanner);
  ProfilePublisher publisher(**bus, channels::kLineProfile, 64, scanner->capacity());
  std::atomic<bool> stop{false};
  std::thread loop(
      [&] { RunScanner(*scanner, stop, [&](const Profile& p) { publisher.Push(p); }); });
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  for (;;) {
    auto handled = (*bus)->HandleOnce(std::chrono::milliseconds(20));
    ASSERT_TRUE(handled.ok());
    std::lock_guard<std::mutex> lock(mutex);
    if (received.size() >= 100 || std::chrono::steady_clock::now() > deadline) break;
  }
  stop = true;
  loop.join();
  publisher.Stop();
  ASSERT_TRUE(decode_errors.empty()) << decode_errors.front();
  ASSERT_GE(received.size(), 100u);
  const sim_wenglor::LineScannerScene scene{sim_wenglor::SceneConfig{}};
  std::vector<sim_wenglor::Column> truth;
  for (std::size_t i = 0; i < received.size(); ++i) {
    const auto& m = received[i];
    if (i > 0) {
      EXPECT_EQ(m.device_counter, received[i - 1].device_counter + 1);
    }
    EXPECT_EQ(m.device_utime, m.device_counter * 1000);
    ASSERT_EQ(m.num_points, 1280);
    scene.Trace(static_cast<double>(m.device_counter) * 1e-3, truth);
    for (std::size_t k = 0; k < truth.size(); ++k) {
      ASSERT_EQ(std::isnan(m.z[k]), !truth[k].hit);
      if (!truth[k].hit) continue;
      ASSERT_NEAR(m.x[k], truth[k].x, 6 * 0.0002);
      ASSERT_NEAR(m.z[k], truth[k].z, 6 * 0.0002);
      ASSERT_EQ(m.intensity[k], static_cast<float>(truth[k].intensity));
    }
  }
  const auto stats = publisher.stats();
  EXPECT_EQ(stats.dropped_queue_full, 0);
  EXPECT_EQ(stats.publish_errors, 0);
}

TEST_F(SimWenglorTest, FullQueueDropsAndCounts) {
  auto bus = OpenLcmBus("memq://");
  ASSERT_TRUE(bus.ok());
  // A publisher whose queue holds 2 profiles; pushing many at once must never block.
  ProfilePublisher publisher(**bus, "X", 2, 16);
  Profile profile;
  profile.Allocate(16);
  profile.num_points = 16;
  int accepted = 0;
  for (int i = 0; i < 1000; ++i) accepted += publisher.Push(profile) ? 1 : 0;
  publisher.Stop();
  const auto stats = publisher.stats();
  EXPECT_EQ(stats.published + stats.dropped_queue_full, 1000);
  EXPECT_EQ(stats.published, accepted);
  EXPECT_GE(stats.published, 2);
  // A profile wider than the slots is dropped, not written past them.
  ProfilePublisher narrow(**bus, "X", 4, 8);
  EXPECT_FALSE(narrow.Push(profile));
}

}  // namespace
}  // namespace selfcal::wenglor
