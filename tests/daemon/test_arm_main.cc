// selfcal-test-arm: the TestArm as a process, for the multi-process daemon tests (udpm:// inside
// tests/netns-run). Runs until SIGTERM. --silence-joints-after S stops the joint states after S s.
#include <CLI/CLI.hpp>
#include <csignal>
#include <iostream>
#include <thread>

#include "daemon/clock.h"
#include "tests/daemon/test_arm.h"

namespace {
volatile std::sig_atomic_t g_stop = 0;
void OnSignal(int) { g_stop = 1; }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"selfcal-test-arm: a stand-in arm and sensor over LCM for daemon tests"};
  std::string url = "udpm://239.255.76.67:7667?ttl=0";
  double silence_joints_after = -1;
  app.add_option("--lcm-url", url, "LCM URL");
  app.add_option("--silence-joints-after", silence_joints_after,
                 "Stop joint states after this many seconds");
  CLI11_PARSE(app, argc, argv);
  auto bus = selfcal::OpenLcmBus(url);
  if (!bus) {
    std::cerr << "error: " << bus.error().message << "\n";
    return 1;
  }
  std::shared_ptr<selfcal::Bus> shared(std::move(bus).value());
  selfcal::daemon::testing::TestArm arm(shared, {});
  std::signal(SIGTERM, OnSignal);
  std::signal(SIGINT, OnSignal);
  const std::int64_t start = selfcal::timing::RealtimeUs();
  while (!g_stop) {
    (void)shared->HandleOnce(std::chrono::milliseconds(2));
    const std::int64_t now = selfcal::timing::RealtimeUs();
    if (silence_joints_after >= 0 &&
        now - start > static_cast<std::int64_t>(silence_joints_after * 1e6)) {
      arm.joints_silent = true;
    }
    arm.Tick(now);
  }
  return 0;
}
