// selfcal-sim-scip: a simulated Hokuyo UTM-30LX-EW speaking SCIP 2.0 over TCP or a pseudo-
// terminal. Prints "port N" or "pty PATH" on stdout once serving; faults on demand from stdin:
//   disconnect SECONDS | reboot SECONDS | corrupt N | stall SECONDS | junk TEXT | quit
// With --scenario, ranges come from core/sim: the scenario's scene seen from the flange of its
// (truly perturbed) robot, whose joint states arrive over LCM.
#include <poll.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <iostream>
#include <sstream>
#include <thread>

#include "protocols/lcm/channels.h"
#include "protocols/program/program.h"
#include "tools/sim_scip/joint_state_feed.h"
#include "tools/sim_scip/scene_range_source.h"
#include "tools/sim_scip/sim_server.h"

namespace {

namespace program = selfcal::program;
using namespace selfcal::sim_scip;

constexpr program::About kAbout{
    "selfcal-sim-scip",
    "selfcal-sim-scip: simulated Hokuyo UTM-30LX-EW (SCIP 2.0) over TCP or a pty.\n"
    "Faults on stdin: disconnect S | reboot S | corrupt N | stall S | junk TEXT | quit"};

struct Settings {
  SimDeviceConfig device;
  SimServerOptions server;
  bool pty = false;
  double latency_ms = SimDeviceConfig{}.latency_us / 1000;
  double jitter_ms = 0;
  std::string scenario;
  std::string lcm_url;
  std::string joint_channel = selfcal::channels::kJointState;
  std::string marker_channel = selfcal::channels::kScanMarker;
};

void DescribeOptions(program::Program& p, Settings& s) {
  p.Flag("--pty", s.pty, "Serve on a pseudo-terminal instead of TCP");
  p.Option("--link", s.server.pty_link, "Keep a symlink to the pty here (stable across faults)");
  p.Option("--address", s.server.address, "TCP address to bind");
  p.Option("--port", s.server.port, "TCP port (0: any free port)");
  p.Option("--drift-ppm", s.device.clock_drift_ppm,
           "Device clock rate error [ppm], added to a --scenario's timing: clock_drift_ppm");
  p.Option("--offset-ms", s.device.clock_offset_ms, "Device counter at start [ms]");
  p.Option("--latency-ms", s.latency_ms, "One-way link latency, each way [ms]")
      ->check(program::kNonNegative);
  p.Option("--jitter-ms", s.jitter_ms, "Uniform jitter added to each one-way latency [ms]")
      ->check(program::kNonNegative);
  p.Option("--motor-speed-error", s.device.motor_speed_error,
           "Mirror rate error relative to the device clock (fraction)");
  p.Option("--serial-baud", s.device.serial_baud,
           "RS-232 emulation: the only rate the device hears (0: USB, any)");
  p.Flag("--answers-while-booting", s.device.answers_while_booting,
         "After `reboot S`: link back at once, TM0, BM and scans denied (10) for S s (a UTM)");
  p.Option("--model", s.device.model, "MODL reported by PP and II");
  p.Option("--serial", s.device.serial, "SERI reported by VV");
  p.Option("--rpm", s.device.rotation_rpm, "Rotation speed (SCAN)")->check(program::kPositive);
  p.Option("--seed", s.device.seed, "Random seed (motor phase, jitter, corruption)");
  p.Option("--scenario", s.scenario,
           "Scenario file: serve ranges cast in its scene from its robot's flange");
  p.Option("--lcm-url", s.lcm_url, "LCM URL for the joint states (--scenario)");
  p.Option("--joint-channel", s.joint_channel, "Channel of selfcal.joint_state_t");
  p.Option("--marker-channel", s.marker_channel,
           "Channel of selfcal.scan_marker_t (--scenario: the walker and the moved box)");
}

// The scene source of --scenario, fed by joint states from the bus on a thread of its own.
class SceneFeed {
 public:
  ~SceneFeed() {
    stop_.store(true);
    if (thread_.joinable()) thread_.join();
    if (rejected_ > 0) spdlog::warn("{} joint states rejected", rejected_);
  }
  // Returns the exit code on failure.
  std::optional<int> Start(const program::Program& p, const Settings& s) {
    auto scene = SceneRangeSource::Create(s.scenario);
    if (!scene) return program::Fail(scene.error().message, program::kExitUsage);
    auto bus = p.OpenBus(s.lcm_url);
    if (!bus) return program::Fail(bus.error().message);
    bus_ = std::move(*bus);
    source_ = std::move(*scene);
    FeedJointStates(*bus_, s.joint_channel, *source_, &rejected_);
    FeedScanMarkers(*bus_, s.marker_channel, *source_, &rejected_);
    spdlog::info("scenario: {} ({} joints), joint states on {}, scan markers on {} at {}",
                 s.scenario, source_->joint_names().size(), s.joint_channel, s.marker_channel,
                 bus_->url());
    thread_ = std::thread([this] {
      while (!stop_.load()) (void)bus_->HandleOnce(std::chrono::milliseconds(50));
    });
    return std::nullopt;
  }
  std::shared_ptr<RangeSource> source() const { return source_; }
  double ClockDriftPpm() const { return source_ ? source_->ClockDriftPpm() : 0; }

 private:
  std::unique_ptr<selfcal::Bus> bus_;
  std::shared_ptr<SceneRangeSource> source_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::int64_t rejected_ = 0;
};

// Applies one fault line from stdin; false for "quit".
bool ApplyFault(SimServer& sim, const std::string& line) {
  std::istringstream words(line);
  std::string verb;
  words >> verb;
  double value = 0;
  if (verb == "quit") return false;
  if (verb == "junk") {
    std::string rest;
    std::getline(words, rest);
    sim.InjectJunk(rest.empty() ? "junk" : rest.substr(1));
  } else if (verb == "disconnect" && words >> value) {
    sim.Disconnect(value);
  } else if (verb == "reboot" && words >> value) {
    sim.Reboot(value);
  } else if (verb == "corrupt" && words >> value) {
    sim.CorruptNextScans(static_cast<int>(value));
  } else if (verb == "stall" && words >> value) {
    sim.Stall(value);
  } else if (!verb.empty()) {
    spdlog::warn(
        "unknown fault '{}' (disconnect S | reboot S | corrupt N | stall S | junk TEXT | quit)",
        line);
    return true;
  }
  spdlog::info("fault: {}", line);
  return true;
}

// Reads faults from stdin until "quit" or a stop signal; after stdin closes, serves on.
void RunFaultConsole(SimServer& sim, const std::atomic<bool>& stop) {
  std::string line;
  bool stdin_open = true;
  while (!stop.load()) {
    if (!stdin_open) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      continue;
    }
    pollfd p{STDIN_FILENO, POLLIN, 0};
    if (poll(&p, 1, 100) <= 0) continue;
    if (!std::getline(std::cin, line)) {
      stdin_open = false;
      continue;
    }
    if (!ApplyFault(sim, line)) return;
  }
}

// Everything after the command line: read files, open the bus, echo, run.
int Start(program::Program& program, Settings& s) {
  s.device.latency_us = s.latency_ms * 1000;
  s.device.latency_jitter_us = s.jitter_ms * 1000;
  s.server.transport =
      s.pty ? SimServerOptions::Transport::kPty : SimServerOptions::Transport::kTcp;
  program.LogConfiguration();
  SceneFeed scene;
  if (!s.scenario.empty()) {
    if (auto exit = scene.Start(program, s)) return *exit;
    if (const double drift = scene.ClockDriftPpm(); drift != 0) {
      s.device.clock_drift_ppm += drift;
      spdlog::info("device clock drift {} ppm (the scenario's {} ppm included)",
                   s.device.clock_drift_ppm, drift);
    }
  }
  auto sim = SimServer::Start(s.device, s.server, scene.source());
  if (!sim) return program::Fail(sim.error().message);
  if (s.pty) {
    std::cout << "pty " << (*sim)->pty_path() << std::endl;
  } else {
    std::cout << "port " << (*sim)->port() << std::endl;
  }
  RunFaultConsole(**sim, program::StopOnSignals());
  (*sim)->Stop();
  return program::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return program::Main<Settings>(argc, argv, kAbout, DescribeOptions, Start);
}
