// CANopen joint states: config (golden values), then the driver through the socket
// seam (a socketpair carrying struct can_frame, the test playing three CiA 402 drives).
#include <gtest/gtest.h>
#include <linux/can.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <thread>

#include "drivers/canopen/canopen_driver.h"
#include "protocols/lcm_log/lcm_codec.h"
#include "protocols/program/program.h"
#include "selfcal/joint_state_t.hpp"
#include "selfcal/robot_driver_status_t.hpp"
#include "tests/yaml_leaf_paths.h"

namespace selfcal::canopen {
namespace {

TEST(CanopenConfig, CountsToRadians) {
  JointConfig joint;
  joint.counts_per_revolution = 65536;
  joint.zero_counts = 1000;
  joint.direction = -1;
  EXPECT_DOUBLE_EQ(joint.ToRadians(1000 + 16384), -M_PI / 2);
}

const char* kConfig = R"(
interface: vcan0
sync: {produce: true, period: 0.004}
start_nodes: true
heartbeat_timeout: 0.2
joints:
  - {name: J1, node: 1, pdo: 1, position_offset: 2, counts_per_revolution: 65536}
  - {name: J2, node: 2, pdo: 1, position_offset: 2, counts_per_revolution: 65536, zero_counts: 100}
  - {name: J3, node: 3, pdo: 2, position_offset: 0, counts_per_revolution: 65536, direction: -1}
)";

TEST(CanopenConfig, StrictReading) {
  auto config = ParseCanopenConfig(kConfig, "arm.yaml");
  ASSERT_TRUE(config.ok()) << config.error().message;
  EXPECT_EQ(config->joints.size(), 3u);
  EXPECT_EQ(config->joints[2].pdo, 2);
  EXPECT_EQ(config->joints[1].zero_counts, 100);
  EXPECT_DOUBLE_EQ(config->sync_period_s, 0.004);
  auto unknown = ParseCanopenConfig(std::string(kConfig) + "gain: 3\n", "arm.yaml");
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.error().message.find("gain"), std::string::npos) << unknown.error().message;
  std::string bad_node = kConfig;
  bad_node.replace(bad_node.find("node: 2"), 7, "node: 200");
  auto node = ParseCanopenConfig(bad_node, "arm.yaml");
  ASSERT_FALSE(node.ok());
  EXPECT_NE(node.error().message.find("joints[1].node"), std::string::npos) << node.error().message;
  std::string twice = kConfig;
  twice.replace(twice.find("node: 3, pdo: 2"), 15, "node: 1, pdo: 1");
  EXPECT_FALSE(ParseCanopenConfig(twice, "arm.yaml").ok());
}

// The shipped file sets every key: the start-up echo holds exactly its key paths, with the values
// read (the node-ID as a number).
TEST(CanopenConfig, TheStartUpEchoNamesEveryKeyOfTheFile) {
  const char* source = std::getenv("SELFCAL_SOURCE_DIR");
  const std::string path = std::string(source ? source : ".") + "/config/drivers/canopen.yaml";
  auto config = ReadCanopenConfig(path);
  ASSERT_TRUE(config.ok()) << config.error().message;
  program::Program program("selfcal-canopen-test", "test");
  DescribeSettings(program, *config);
  const std::string echo = program.Configuration();
  auto keys = testing::LeafPaths(YAML::LoadFile(path));
  auto echoed = testing::EchoedKeys(echo);
  std::sort(keys.begin(), keys.end());
  std::sort(echoed.begin(), echoed.end());
  EXPECT_EQ(echoed, keys) << echo;
  EXPECT_EQ(testing::EchoedValue(echo, "sync.period"), "0.005");
  EXPECT_EQ(testing::EchoedValue(echo, "joints[2].node"), "3");
  EXPECT_EQ(testing::EchoedValue(echo, "joints[2].direction"), "-1");
  EXPECT_EQ(testing::EchoedValue(echo, "interface"), "can0");
}

// The test side of the socketpair plays the drives.
struct Drives {
  int fd;
  CanFrame Read() {
    can_frame raw{};
    const ssize_t n = ::read(fd, &raw, sizeof(raw));
    EXPECT_EQ(n, static_cast<ssize_t>(sizeof(raw)));
    CanFrame frame;
    frame.id = raw.can_id;
    frame.length = raw.len;
    std::memcpy(frame.data.data(), raw.data, raw.len);
    return frame;
  }
  bool Pending() {
    can_frame raw{};
    return ::recv(fd, &raw, sizeof(raw), MSG_PEEK | MSG_DONTWAIT) > 0;
  }
  void Write(const CanFrame& frame) {
    can_frame raw{};
    raw.can_id = frame.id;
    raw.len = frame.length;
    std::memcpy(raw.data, frame.data.data(), frame.length);
    ASSERT_EQ(::write(fd, &raw, sizeof(raw)), static_cast<ssize_t>(sizeof(raw)));
  }
  static CanFrame Tpdo(std::uint32_t cob, int offset, std::int32_t counts) {
    CanFrame f;
    f.id = cob;
    f.length = static_cast<std::uint8_t>(offset + 4);
    f.data[0] = 0x37;
    f.data[1] = 0x06;
    for (int b = 0; b < 4; ++b) {
      f.data[static_cast<std::size_t>(offset + b)] =
          static_cast<std::uint8_t>(static_cast<std::uint32_t>(counts) >> (8 * b));
    }
    return f;
  }
};

TEST(CanopenDriver, SyncTimestampedJointStatesThroughTheSocketSeam) {
  int pair[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET, 0, pair), 0);
  auto bus = OpenLcmBus("memq://");
  ASSERT_TRUE(bus.ok());
  std::vector<selfcal::joint_state_t> states;
  std::vector<std::string> events;
  (*bus)->Subscribe("SELFCAL_JOINT_STATE", [&](const BusMessage& m) {
    states.push_back(DecodeLcm<selfcal::joint_state_t>(m.data, m.channel).value());
  });
  (*bus)->Subscribe("SELFCAL_ROBOT_STATUS", [&](const BusMessage& m) {
    auto s = DecodeLcm<selfcal::robot_driver_status_t>(m.data, m.channel).value();
    if (s.event == selfcal::robot_driver_status_t::EVENT_SESSION) events.push_back(s.message);
  });
  CanopenDriverOptions options;
  options.config = ParseCanopenConfig(kConfig, "arm.yaml").value();
  options.clock.settle_s = 0.1;
  options.clock.settle_samples = 10;
  CanopenDriver driver(options, CanSocket::FromFd(pair[0]), **bus);
  Drives drives{pair[1]};

  std::vector<std::int64_t> sync_host_us;
  std::vector<CanFrame> nmt;
  std::int64_t syncs = 0;
  const auto start = std::chrono::steady_clock::now();
  bool booted = false;
  while (std::chrono::steady_clock::now() - start < std::chrono::milliseconds(600)) {
    ASSERT_TRUE(driver.SpinOnce(std::chrono::microseconds(500)).ok());
    while ((*bus)->HandleOnce(std::chrono::milliseconds(0)).value()) {
    }
    while (drives.Pending()) {
      const CanFrame f = drives.Read();
      if (f.id == 0x000) nmt.push_back(f);
      if (f.id != 0x080) continue;
      timespec ts{};
      clock_gettime(CLOCK_REALTIME, &ts);
      sync_host_us.push_back(static_cast<std::int64_t>(ts.tv_sec) * 1000000 + ts.tv_nsec / 1000);
      ++syncs;
      // Every drive answers the SYNC: J1 turns at 1 rad/s (counts per 4 ms), J2 stands at
      // zero_counts + 16384 (pi/2), J3 at -8192 counts (direction -1: +pi/4). Node 3 skips
      // SYNC 5 (a lost TPDO).
      const auto j1 = static_cast<std::int32_t>(
          std::llround(static_cast<double>(syncs) * 0.004 * 65536 / (2 * M_PI)));
      drives.Write(Drives::Tpdo(0x181, 2, j1));
      drives.Write(Drives::Tpdo(0x182, 2, 100 + 16384));
      if (syncs != 5) drives.Write(Drives::Tpdo(0x283, 0, -8192));
      // Heartbeats of nodes 1..3 every 10th SYNC; node 3 boots first, and falls silent later.
      if (!booted) {
        drives.Write(ParseCansend("703#00").value());
        booted = true;
      }
      if (syncs % 10 == 0) {
        drives.Write(ParseCansend("701#05").value());
        drives.Write(ParseCansend("702#05").value());
        if (syncs < 60) drives.Write(ParseCansend("703#05").value());
      }
    }
  }
  for (int i = 0; i < 20; ++i) (void)(*bus)->HandleOnce(std::chrono::milliseconds(0));
  ASSERT_GT(syncs, 100);
  // NMT start to each node at start, and again to node 3 after its boot-up.
  ASSERT_GE(nmt.size(), 4u);
  EXPECT_EQ(FormatCansend(nmt[0]), "000#0101");
  EXPECT_EQ(FormatCansend(nmt[1]), "000#0102");
  EXPECT_EQ(FormatCansend(nmt[2]), "000#0103");
  EXPECT_EQ(FormatCansend(nmt[3]), "000#0103");
  // Joint states: scaled from counts, stamped with the SYNC instant.
  ASSERT_GT(states.size(), 50u);
  EXPECT_EQ(states.front().names, (std::vector<std::string>{"J1", "J2", "J3"}));
  double worst_time_us = 0;
  std::vector<double> time_errors_us;
  for (const auto& s : states) {
    EXPECT_NEAR(s.positions[1], M_PI / 2, 1e-12);
    EXPECT_NEAR(s.positions[2], M_PI / 4, 1e-12);
    const auto index = static_cast<std::size_t>(s.device_utime / 4000);  // SYNC index
    EXPECT_EQ(s.device_utime % 4000, 0);
    ASSERT_LT(index, sync_host_us.size());
    EXPECT_NEAR(s.positions[0],
                std::round((static_cast<double>(index) + 1) * 0.004 * 65536 / (2 * M_PI)) * 2 *
                    M_PI / 65536,
                1e-12);
    if (!std::isnan(s.velocities[0])) {
      EXPECT_NEAR(s.velocities[0], 1.0, 0.05);
    }
    // The driver sends SYNC right after its own clock reading; the test reads it later.
    const double error = static_cast<double>(s.utime - sync_host_us[index]);
    time_errors_us.push_back(std::abs(error));
    worst_time_us = std::max(worst_time_us, std::abs(error));
  }
  std::sort(time_errors_us.begin(), time_errors_us.end());
  const double median_us = time_errors_us[time_errors_us.size() / 2];
  std::printf(
      "%zu joint states from %lld SYNCs; utime vs the drive side's receive time of the "
      "SYNC: median %.0f us, worst %.0f us\n",
      states.size(), static_cast<long long>(syncs), median_us, worst_time_us);
  // The drive side is this test thread, which reads the SYNC late whenever a loaded machine
  // preempts it: only the median is a statement about the driver (exact timing is checked
  // deterministically in SyncInstantsMapToHostTimeUnderDriftAndJitter).
  EXPECT_LT(median_us, 2000.0);
  EXPECT_EQ(driver.source().incomplete_syncs(), 1);
  // Node events: boot-up, operational, node 3's heartbeat lost.
  auto has = [&](const std::string& text) {
    for (const auto& e : events) {
      if (e.find(text) != std::string::npos) return true;
    }
    return false;
  };
  EXPECT_TRUE(has("node 3: boot-up"));
  EXPECT_TRUE(has("node 1: operational"));
  EXPECT_TRUE(has("node 3: no heartbeat"));
  EXPECT_FALSE(has("node 1: no heartbeat"));
  ::close(pair[1]);
}

// Deterministic: another master's SYNC every 5 ms by a clock 50 ppm fast, received with 20 to
// 300 us of delay, TPDOs after it; utime must be the SYNC instant.
TEST(CanopenSource, SyncInstantsMapToHostTimeUnderDriftAndJitter) {
  CanopenConfig config = ParseCanopenConfig(kConfig, "arm.yaml").value();
  config.produce_sync = false;
  config.sync_period_s = 0.005;
  config.heartbeat_timeout_s = 100;
  CanopenSource source(config);
  std::mt19937 random(3);
  std::uniform_real_distribution<double> delay_us(20, 300);
  const std::int64_t t0 = 1700000000000000;
  double worst_us = 0;
  std::size_t samples = 0;
  for (int k = 0; k < 600; ++k) {
    // The master's k-th SYNC, at host time t0 + k * 5 ms / (1 + 50 ppm).
    const auto instant = t0 + static_cast<std::int64_t>(k * 5000.0 / (1 + 50e-6));
    const auto received = instant + static_cast<std::int64_t>(delay_us(random));
    (void)source.Tick(received);
    source.OnFrame(MakeSync(), received);
    source.OnFrame(Drives::Tpdo(0x181, 2, k), received + 100);
    source.OnFrame(Drives::Tpdo(0x182, 2, 0), received + 150);
    source.OnFrame(Drives::Tpdo(0x283, 0, 0), received + 200);
    for (const JointSample& s : source.TakeSamples()) {
      ++samples;
      EXPECT_EQ(s.sync_index, k);
      worst_us = std::max(worst_us, std::abs(static_cast<double>(s.host_us - instant)));
    }
  }
  std::printf("%zu samples, SYNC instant error worst %.0f us (delays 20..300 us)\n", samples,
              worst_us);
  EXPECT_GT(samples, 400u);
  EXPECT_LT(worst_us, 100.0);
  EXPECT_NEAR(source.clock().drift_ppm(), -50.0, 10.0);
  EXPECT_EQ(source.incomplete_syncs(), 0);
}

// The SYNC counter (CiA 301: 1 .. overflow) says how many SYNCs were missed, across its wrap;
// producing SYNC, ours count 1 .. overflow.
TEST(CanopenSource, SyncCounterStepsCountMissedSyncs) {
  CanopenConfig config = ParseCanopenConfig(kConfig, "arm.yaml").value();
  config.produce_sync = false;
  config.sync_counter_overflow = 4;
  config.heartbeat_timeout_s = 100;
  CanopenSource follower(config);
  const std::int64_t t0 = 1700000000000000;
  const std::uint8_t counters[] = {3, 4, 2, 3, 3};  // 1 missed across the wrap; then 4 missed
  const std::int64_t expected[] = {0, 1, 3, 4, 8};
  for (std::size_t k = 0; k < std::size(counters); ++k) {
    follower.OnFrame(MakeSync(counters[k]), t0 + static_cast<std::int64_t>(k) * 5000);
    EXPECT_EQ(follower.syncs(), expected[k]) << k;
  }

  config.produce_sync = true;
  CanopenSource producer(config);
  std::vector<int> sent;
  for (int k = 0; k < 6; ++k) {
    for (const CanFrame& frame : producer.Tick(t0 + k * 5000)) {
      if (frame.id == 0x080) sent.push_back(DecodeSyncCounter(frame).value());
    }
  }
  EXPECT_EQ(sent, (std::vector<int>{1, 2, 3, 4, 1, 2}));
  EXPECT_EQ(producer.syncs(), 5);
}

TEST(CanopenDriver, RealSocketCanOrASkipWithTheReason) {
  auto socket = CanSocket::OpenSocketCan("vcan0");
  if (!socket.ok() && socket.error().message.find("no AF_CAN") != std::string::npos) {
    GTEST_SKIP() << "this kernel has no AF_CAN (SocketCAN), so no vcan: " << socket.error().message
                 << " (the driver is tested through the socket seam and the preload shim)";
  }
  if (!socket.ok()) GTEST_SKIP() << "SocketCAN exists but no vcan0: " << socket.error().message;
  // A kernel with vcan0: a second socket sees our frame.
  auto peer = CanSocket::OpenSocketCan("vcan0");
  ASSERT_TRUE(peer.ok()) << peer.error().message;
  ASSERT_TRUE((*socket)->Write(MakeSync(3)).ok());
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  auto frame = (*peer)->Read();
  ASSERT_TRUE(frame.ok());
  ASSERT_TRUE(frame->has_value());
  EXPECT_EQ(FormatCansend(**frame), "080#03");
}

}  // namespace
}  // namespace selfcal::canopen
