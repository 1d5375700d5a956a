// selfcal-canopen as a process with can-utils as real peers: cansend plays the drives (SYNC from
// another master, TPDOs, heartbeats), candump records what the driver sends (NMT start). All of
// them run under the preload shim (drivers/canopen/shim) inside `unshare -rn`, because this
// kernel has no AF_CAN. The driver writes its LCM messages to a file:// log that we decode.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "protocols/canopen/canopen_frames.h"
#include "protocols/lcm_log/lcm_codec.h"
#include "protocols/lcm_log/lcm_log.h"
#include "selfcal/joint_state_t.hpp"
#include "selfcal/robot_driver_status_t.hpp"
#include "tests/time_scale.h"

namespace selfcal::canopen {
namespace {

std::string Hex32(std::int32_t v) {
  char text[16];
  const auto u = static_cast<std::uint32_t>(v);
  std::snprintf(text, sizeof(text), "%02X%02X%02X%02X", u & 0xff, (u >> 8) & 0xff, (u >> 16) & 0xff,
                (u >> 24) & 0xff);
  return text;
}

bool Have(const char* program) {
  return std::system((std::string("command -v ") + program + " >/dev/null 2>&1").c_str()) == 0;
}

TEST(CanopenShim, DecodesFramesSentByCansend) {
  if (!Have("cansend") || !Have("candump")) GTEST_SKIP() << "can-utils not installed";
  if (std::system("unshare -rn true >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "unshare -rn is not permitted here (no user/network namespaces)";
  }
  // The drives' 10 ms SYNC cycle comes from cansend processes; under qemu-user each takes about
  // 67 ms and the cycle about 200 ms: in one run of three the driver's SYNC clock settled so late
  // that 3 of the 12 cycles gave joint states.
  if (selfcal::testing::Emulated())
    GTEST_SKIP() << "an emulated cansend cannot keep the drives' 10 ms SYNC cycle";
  const auto dir =
      std::filesystem::temp_directory_path() / ("selfcal_canshim_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  {
    std::ofstream config(dir / "arm.yaml");
    config << "interface: vcan0\n"
              "sync: {produce: false, period: 0.01}\n"
              "start_nodes: true\n"
              "heartbeat_timeout: 5\n"
              "joints:\n"
              "  - {name: J1, node: 1, pdo: 1, position_offset: 2, counts_per_revolution: 65536}\n"
              "  - {name: J2, node: 2, pdo: 1, position_offset: 2, counts_per_revolution: 65536, "
              "direction: -1}\n";
  }
  // The drives' side: boot-up of node 2, then 12 SYNC cycles with both TPDOs; J1 at 1000 * k
  // counts, J2 at -4096 counts (direction -1: +pi/8).
  std::ostringstream drives;
  drives << "cansend vcan0 702#00\n";
  for (int k = 1; k <= 12; ++k) {
    drives << "cansend vcan0 080#\n"
           << "cansend vcan0 181#3706" << Hex32(1000 * k) << "\n"
           << "cansend vcan0 182#3706" << Hex32(-4096) << "\n"
           << "sleep 0.01\n";
  }
  drives << "cansend vcan0 701#05\n";
  {
    std::ofstream script(dir / "run.sh");
    script << "set -e\n"
              "cd "
           << dir.string()
           << "\n"
              "export LD_PRELOAD=" SELFCAL_CANSHIM_PATH
              "\n"
              "export SELFCAL_CANSHIM_INTERFACES=vcan0\n"
              "candump -L vcan0 > candump.log 2>candump.err &\n"
              "dump=$!\n"
              "sleep 0.2\n" SELFCAL_CANOPEN_BIN " --config arm.yaml --lcm-url 'file://"
           << dir.string()
           << "/out.lcmlog?mode=w' --duration 2.5 --clock-settle 0.02 --clock-settle-samples 3"
              " > driver.log 2>&1 &\n"
              "driver=$!\n"
              "sleep 0.5\n"
           << drives.str()
           << "wait $driver\n"
              "kill $dump; wait $dump || true\n";
  }
  const std::string command =
      "unshare -rn sh " + (dir / "run.sh").string() + " > " + (dir / "run.log").string() + " 2>&1";
  const int rc = std::system(command.c_str());
  auto slurp = [&](const char* name) {
    std::ifstream in(dir / name);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  };
  ASSERT_EQ(rc, 0) << slurp("run.log") << slurp("driver.log");

  // What candump saw the driver send: NMT start to both nodes, again to node 2 after boot-up.
  const std::string dump = slurp("candump.log");
  EXPECT_NE(dump.find("vcan0 000#0101"), std::string::npos) << dump;
  EXPECT_NE(dump.find("vcan0 000#0102"), std::string::npos) << dump;
  std::size_t starts_node2 = 0;
  for (std::size_t p = dump.find("000#0102"); p != std::string::npos;
       p = dump.find("000#0102", p + 1)) {
    ++starts_node2;
  }
  EXPECT_EQ(starts_node2, 2u) << dump;
  // candump also saw cansend's frames: the shim is one bus for all.
  EXPECT_NE(dump.find("vcan0 080#"), std::string::npos);

  // What the driver published.
  auto reader = LcmLogReader::Open((dir / "out.lcmlog").string());
  ASSERT_TRUE(reader.ok()) << reader.error().message << slurp("driver.log");
  std::vector<selfcal::joint_state_t> states;
  std::vector<std::string> events;
  LogEvent event;
  while (reader->Next(event)) {
    if (event.channel == "SELFCAL_JOINT_STATE") {
      auto s = DecodeLcm<selfcal::joint_state_t>(event.data, "log");
      ASSERT_TRUE(s.ok()) << s.error().message;
      states.push_back(*s);
    } else if (event.channel == "SELFCAL_ROBOT_STATUS") {
      auto s = DecodeLcm<selfcal::robot_driver_status_t>(event.data, "log");
      ASSERT_TRUE(s.ok()) << s.error().message;
      events.push_back(s->message);
    }
  }
  std::printf("%zu joint states decoded from cansend's frames\n", states.size());
  ASSERT_GE(states.size(), 8u) << slurp("driver.log");
  std::int64_t previous_utime = 0;
  for (const auto& s : states) {
    const auto k = s.device_utime / 10000 + 1;  // SYNC index from 0 -> cycle k from 1
    EXPECT_NEAR(s.positions[0], 1000.0 * static_cast<double>(k) * 2 * M_PI / 65536, 1e-12);
    EXPECT_NEAR(s.positions[1], M_PI / 8, 1e-12);
    EXPECT_GT(s.utime, previous_utime);
    previous_utime = s.utime;
  }
  EXPECT_EQ(states.back().device_utime, 11 * 10000);  // the 12th SYNC
  bool booted = false;
  for (const auto& e : events) booted = booted || e == "node 2: boot-up";
  EXPECT_TRUE(booted);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace selfcal::canopen
