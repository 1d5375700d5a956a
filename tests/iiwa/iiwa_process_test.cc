// The two programs as processes: selfcal-sim-fri and selfcal-iiwa over UDP on 127.0.0.1, the
// driver's LCM messages written to a file:// log; --help, and bad input answered with "error:".
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "drake/lcmt_iiwa_status.hpp"
#include "protocols/lcm_log/lcm_codec.h"
#include "protocols/lcm_log/lcm_log.h"
#include "selfcal/joint_state_t.hpp"
#include "selfcal/robot_driver_status_t.hpp"

namespace selfcal {
namespace {

std::string Source() {
  const char* dir = std::getenv("SELFCAL_SOURCE_DIR");
  return dir ? dir : ".";
}

// A UDP port that is free right now (bound to port 0, then released).
int FreeUdpPort() {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a));
  socklen_t n = sizeof(a);
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &n);
  ::close(fd);
  return ntohs(a.sin_port);
}

std::string RunCommand(const std::string& command, int* rc) {
  const std::string out =
      (std::filesystem::temp_directory_path() / ("selfcal_iiwa_cmd_" + std::to_string(::getpid())))
          .string();
  *rc = std::system((command + " > " + out + " 2>&1").c_str());
  std::ifstream in(out);
  std::stringstream s;
  s << in.rdbuf();
  std::filesystem::remove(out);
  return s.str();
}

// A key file of 64 hex characters with `mode`.
std::string WriteKeyFile(const std::filesystem::path& path, std::filesystem::perms mode) {
  std::ofstream(path) << "00112233445566778899aabbccddeeff0123456789abcdeffedcba9876543210\n";
  std::filesystem::permissions(path, mode);
  return path.string();
}

TEST(IiwaProcesses, HelpAndBadInput) {
  int rc = 0;
  const std::string help = RunCommand(SELFCAL_IIWA_BIN " --help", &rc);
  EXPECT_NE(help.find("--fri-port"), std::string::npos);
  EXPECT_NE(help.find("--key-file"), std::string::npos);
  EXPECT_NE(help.find("--follow-iiwa-command"), std::string::npos);
  EXPECT_EQ(rc, 0);
  EXPECT_NE(RunCommand(SELFCAL_SIM_FRI_BIN " --help", &rc).find("--drift-ppm"), std::string::npos);
  EXPECT_EQ(rc, 0);
  std::string out =
      RunCommand(SELFCAL_IIWA_BIN " --model /nonexistent.yaml --lcm-url memq://", &rc);
  EXPECT_NE(rc, 0);
  EXPECT_NE(out.find("error: "), std::string::npos) << out;
  EXPECT_NE(out.find("/nonexistent.yaml"), std::string::npos) << out;
  out = RunCommand(SELFCAL_SIM_FRI_BIN " --model " + Source() +
                       "/config/robots/kuka_lbr_iiwa_r840.yaml --initial-position 1 2 3",
                   &rc);
  EXPECT_NE(rc, 0);
  EXPECT_NE(out.find("error: "), std::string::npos) << out;
  out = RunCommand(SELFCAL_IIWA_BIN " --start-tolerance -1", &rc);
  EXPECT_NE(rc, 0);
  EXPECT_NE(out.find("error: "), std::string::npos) << out;
  // The key: a missing file and one that others may read are errors naming the file.
  const std::string model = " --model " + Source() + "/config/robots/kuka_lbr_iiwa_r840.yaml";
  out =
      RunCommand(SELFCAL_IIWA_BIN + model + " --lcm-url memq:// --key-file /nonexistent.key", &rc);
  EXPECT_NE(rc, 0);
  EXPECT_NE(out.find("error: /nonexistent.key"), std::string::npos) << out;
  const auto readable =
      std::filesystem::temp_directory_path() / ("selfcal_iiwa_key_" + std::to_string(::getpid()));
  using std::filesystem::perms;
  WriteKeyFile(readable, perms::owner_read | perms::owner_write | perms::group_read);
  out = RunCommand(SELFCAL_IIWA_BIN + model + " --lcm-url memq:// --key-file " + readable.string(),
                   &rc);
  std::filesystem::remove(readable);
  EXPECT_NE(rc, 0);
  EXPECT_NE(out.find("group or others may access it"), std::string::npos) << out;
}

TEST(IiwaProcesses, SimulatorAndDriverOverLoopback) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("selfcal_iiwa_proc_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string model = Source() + "/config/robots/kuka_lbr_iiwa_r840.yaml";
  const int port = FreeUdpPort();
  const std::string log = (dir / "driver.lcmlog").string();
  using std::filesystem::perms;
  const std::string key = WriteKeyFile(dir / "daemon.key", perms::owner_read | perms::owner_write);
  const std::string script =
      SELFCAL_IIWA_BIN " --model " + model + " --bind-host 127.0.0.1 --fri-port " +
      std::to_string(port) + " --key-file " + key + " --lcm-url 'file://" + log +
      "?mode=w' --duration 2.5 > " + (dir / "iiwa.log").string() +
      " 2>&1 & iiwa=$!; sleep 0.2; " SELFCAL_SIM_FRI_BIN " --model " + model + " --client-port " +
      std::to_string(port) + " --period 0.005 --drift-ppm 50 --duration 2 > " +
      (dir / "sim.log").string() + " 2>&1; wait $iiwa";
  int rc = 0;
  const std::string out = RunCommand("sh -c \"" + script + "\"", &rc);
  ASSERT_EQ(rc, 0) << out;
  auto reader = LcmLogReader::Open(log);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  int joint_states = 0, iiwa_status = 0;
  bool commanding = false;
  LogEvent event;
  while (reader->Next(event)) {
    if (event.channel == "SELFCAL_JOINT_STATE") {
      ASSERT_TRUE(DecodeLcm<selfcal::joint_state_t>(event.data, log).ok());
      ++joint_states;
    } else if (event.channel == "IIWA_STATUS") {
      ASSERT_TRUE(DecodeLcm<drake::lcmt_iiwa_status>(event.data, log).ok());
      ++iiwa_status;
    } else if (event.channel == "SELFCAL_ROBOT_STATUS") {
      auto s = DecodeLcm<selfcal::robot_driver_status_t>(event.data, log);
      ASSERT_TRUE(s.ok());
      commanding = commanding || s->session_state == 4;
    }
  }
  std::ifstream iiwa_log(dir / "iiwa.log");
  std::stringstream iiwa_text;
  iiwa_text << iiwa_log.rdbuf();
  EXPECT_EQ(iiwa_text.str().find("no --key-file"), std::string::npos) << iiwa_text.str();
  EXPECT_EQ(iiwa_text.str().find("INSECURE"), std::string::npos) << iiwa_text.str();
  std::ifstream sim_log(dir / "sim.log");
  std::stringstream sim_text;
  sim_text << sim_log.rdbuf();
  std::printf("%d joint states, %d IIWA_STATUS from the process pair\n", joint_states, iiwa_status);
  // 2 s at 200 Hz, minus the start and the 0.5 s the clock filter needs to settle.
  EXPECT_GT(joint_states, 150) << sim_text.str();
  EXPECT_EQ(joint_states, iiwa_status);
  EXPECT_TRUE(commanding);
  EXPECT_NE(sim_text.str().find("0 velocity violations"), std::string::npos) << sim_text.str();
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace selfcal
