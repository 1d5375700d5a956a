// The two processes as a site runs them: selfcal-sim-scip on a pseudo-terminal (faults typed on
// its stdin) and selfcal-hokuyo publishing to a real LCM log (file://). The log is read back and
// every scan checked against the simulator's pattern.
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "protocols/lcm/channels.h"
#include "protocols/lcm_log/lcm_log.h"
#include "selfcal/range_scan_t.hpp"
#include "tests/time_scale.h"
#include "tools/sim_scip/range_source.h"

extern char** environ;

namespace {

struct Child {
  pid_t pid = -1;
  int stdin_fd = -1;
  int stdout_fd = -1;
  int stderr_fd = -1;
};

Child Spawn(const std::vector<std::string>& args) {
  int in[2], out[2], err[2];
  EXPECT_EQ(pipe(in), 0);
  EXPECT_EQ(pipe(out), 0);
  EXPECT_EQ(pipe(err), 0);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, in[0], 0);
  posix_spawn_file_actions_adddup2(&actions, out[1], 1);
  posix_spawn_file_actions_adddup2(&actions, err[1], 2);
  for (int fd : {in[1], out[0], err[0], in[0], out[1], err[1]}) {
    posix_spawn_file_actions_addclose(&actions, fd);
  }
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  Child child;
  EXPECT_EQ(posix_spawn(&child.pid, argv[0], &actions, nullptr, argv.data(), environ), 0);
  posix_spawn_file_actions_destroy(&actions);
  close(in[0]);
  close(out[1]);
  close(err[1]);
  child.stdin_fd = in[1];
  child.stdout_fd = out[0];
  child.stderr_fd = err[0];
  return child;
}

std::string ReadAll(int fd) {
  std::string text;
  char buffer[4096];
  ssize_t n;
  while ((n = read(fd, buffer, sizeof(buffer))) > 0)
    text.append(buffer, static_cast<std::size_t>(n));
  return text;
}

// Exit status, or -1 if the child did not exit within `timeout_s` (then it is killed).
int WaitExit(pid_t pid, double timeout_s) {
  const auto until = std::chrono::steady_clock::now() +
                     std::chrono::milliseconds(static_cast<int>(timeout_s * 1000));
  int status = 0;
  while (std::chrono::steady_clock::now() < until) {
    if (waitpid(pid, &status, WNOHANG) == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  kill(pid, SIGKILL);
  waitpid(pid, &status, 0);
  return -1;
}

void Say(const Child& child, const std::string& line) {
  const std::string text = line + "\n";
  ASSERT_EQ(write(child.stdin_fd, text.data(), text.size()), static_cast<ssize_t>(text.size()));
}

TEST(HokuyoProcesses, HelpAndBadInput) {
  for (const char* binary : {SELFCAL_HOKUYO_BIN, SELFCAL_SIM_SCIP_BIN}) {
    Child help = Spawn({binary, "--help"});
    close(help.stdin_fd);
    EXPECT_NE(ReadAll(help.stdout_fd).find("Usage"), std::string::npos) << binary;
    EXPECT_EQ(WaitExit(help.pid, 5), 0) << binary;
    Child bad = Spawn({binary, "--no-such-flag"});
    close(bad.stdin_fd);
    EXPECT_EQ(ReadAll(bad.stderr_fd).rfind("error: ", 0), 0u) << binary;
    EXPECT_NE(WaitExit(bad.pid, 5), 0) << binary;
  }
  // No device given; a config file with an unknown key names file and key.
  Child none = Spawn({SELFCAL_HOKUYO_BIN});
  EXPECT_NE(ReadAll(none.stderr_fd).find("error: give exactly one of device, host or usb"),
            std::string::npos);
  EXPECT_EQ(WaitExit(none.pid, 5), 2);
  const std::string config = "/tmp/selfcal-hokuyo-bad-" + std::to_string(getpid()) + ".yaml";
  {
    FILE* f = std::fopen(config.c_str(), "w");
    std::fputs("device: /dev/ttyACM0\nbaudrate: 115200\n", f);
    std::fclose(f);
  }
  Child bad_config = Spawn({SELFCAL_HOKUYO_BIN, "--config", config});
  const std::string error = ReadAll(bad_config.stderr_fd);
  EXPECT_NE(error.find("baudrate"), std::string::npos) << error;
  EXPECT_NE(error.find(config), std::string::npos) << error;
  EXPECT_EQ(WaitExit(bad_config.pid, 5), 2);
  std::remove(config.c_str());
}

TEST(HokuyoProcesses, DriverStreamsTheSimulatorToAnLcmLogThroughFaults) {
  const std::string base = "/tmp/selfcal-hokuyo-proc-" + std::to_string(getpid());
  const std::string link = base + "-tty";
  const std::string log = base + ".lcmlog";
  std::filesystem::remove(log);
  Child sim = Spawn(
      {SELFCAL_SIM_SCIP_BIN, "--pty", "--link", link, "--drift-ppm", "50", "--jitter-ms", "1"});
  // "pty <link>" once serving.
  std::string first_line;
  char c;
  while (read(sim.stdout_fd, &c, 1) == 1 && c != '\n') first_line.push_back(c);
  ASSERT_EQ(first_line, "pty " + link);

  Child driver = Spawn({SELFCAL_HOKUYO_BIN, "--device", link, "--lcm-url",
                        "file://" + log + "?mode=w", "--backoff-max", "0.3"});
  std::this_thread::sleep_for(selfcal::testing::Scaled(std::chrono::milliseconds(1500)));
  Say(sim, "corrupt 3");
  std::this_thread::sleep_for(selfcal::testing::Scaled(std::chrono::milliseconds(500)));
  Say(sim, "disconnect 0.3");
  std::this_thread::sleep_for(selfcal::testing::Scaled(std::chrono::milliseconds(1500)));
  Say(sim, "stall 1.5");
  std::this_thread::sleep_for(selfcal::testing::Scaled(std::chrono::milliseconds(2000)));
  kill(driver.pid, SIGINT);
  EXPECT_EQ(WaitExit(driver.pid, 5), 0) << "the driver must stop on SIGINT";
  const std::string driver_log = ReadAll(driver.stderr_fd);
  Say(sim, "quit");
  EXPECT_EQ(WaitExit(sim.pid, 5), 0);

  EXPECT_NE(driver_log.find("config: device=" + link), std::string::npos) << driver_log;
  EXPECT_NE(driver_log.find("checksum mismatch"), std::string::npos) << driver_log;
  EXPECT_NE(driver_log.find("stream stalled"), std::string::npos) << driver_log;

  auto reader = selfcal::LcmLogReader::Open(log);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  selfcal::LogEvent event;
  int scans = 0;
  int corrupted = 0;
  std::int64_t last_counter = -1;
  std::int64_t last_utime = 0;
  while (reader->Next(event)) {
    ASSERT_EQ(event.channel, selfcal::channels::kRangeScan);
    auto scan = selfcal::DecodeLcm<selfcal::range_scan_t>(event.data, "log");
    ASSERT_TRUE(scan.ok()) << scan.error().message;
    ASSERT_EQ(scan->num_ranges, 1081);
    const auto ts = static_cast<std::uint32_t>((scan->device_utime / 1000) & 0xFFFFFF);
    for (int i = 0; i < scan->num_ranges; ++i) {
      const float expected =
          static_cast<float>(selfcal::sim_scip::PatternRangeSource::Range(i, ts)) * 1e-3f;
      if (scan->ranges[static_cast<std::size_t>(i)] != expected) {
        ++corrupted;
        break;
      }
    }
    EXPECT_GT(scan->scan_counter, last_counter);
    EXPECT_GT(scan->utime, last_utime);
    last_counter = scan->scan_counter;
    last_utime = scan->utime;
    ++scans;
  }
  EXPECT_EQ(corrupted, 0);
  // About 5.5 s of streaming minus the outages: well over 100 scans.
  EXPECT_GT(scans, 100);
  std::filesystem::remove(log);
}

}  // namespace
