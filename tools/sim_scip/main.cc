// selfcal-sim-scip: a simulated Hokuyo UTM-30LX-EW speaking SCIP 2.0 over TCP or a pseudo-
// terminal. Prints "port N" or "pty PATH" on stdout once serving; faults on demand from stdin:
//   disconnect SECONDS | reboot SECONDS | corrupt N | stall SECONDS | junk TEXT | quit
// With --scenario, ranges come from core/sim: the scenario's scene seen from the flange of its
// (truly perturbed) robot, whose joint states arrive over LCM.
#include <poll.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <iostream>
#include <sstream>
#include <thread>

#include "tools/sim_scip/sim_server.h"
#ifdef SELFCAL_SIM_SCIP_WITH_SCENE
#include "protocols/lcm/channels.h"
#include "tools/sim_scip/joint_state_feed.h"
#include "tools/sim_scip/scene_range_source.h"
#endif

namespace {
std::atomic<bool> g_stop{false};
void OnSignal(int) { g_stop.store(true); }
}  // namespace

int main(int argc, char** argv) {
  using namespace selfcal::sim_scip;
  CLI::App app{
      "selfcal-sim-scip: simulated Hokuyo UTM-30LX-EW (SCIP 2.0) over TCP or a pty.\n"
      "Faults on stdin: disconnect S | reboot S | corrupt N | stall S | junk TEXT | quit"};
  SimDeviceConfig device;
  SimServerOptions server;
  bool pty = false;
  double latency_ms = device.latency_us / 1000;
  double jitter_ms = 0;
  app.add_flag("--pty", pty, "Serve on a pseudo-terminal instead of TCP");
  app.add_option("--link", server.pty_link,
                 "Keep a symlink to the pty here (stable across faults)");
  app.add_option("--address", server.address, "TCP address to bind (127.0.0.1)");
  app.add_option("--port", server.port, "TCP port (0: any free port)");
  app.add_option("--drift-ppm", device.clock_drift_ppm, "Device clock rate error [ppm]");
  app.add_option("--offset-ms", device.clock_offset_ms, "Device counter at start [ms]");
  app.add_option("--latency-ms", latency_ms, "One-way link latency, each way [ms]");
  app.add_option("--jitter-ms", jitter_ms, "Uniform jitter added to each one-way latency [ms]");
  app.add_option("--motor-speed-error", device.motor_speed_error,
                 "Mirror rate error relative to the device clock (fraction)");
  app.add_option("--serial-baud", device.serial_baud,
                 "RS-232 emulation: the only rate the device hears (0: USB, any)");
  app.add_option("--model", device.model, "MODL reported by PP and II");
  app.add_option("--serial", device.serial, "SERI reported by VV");
  app.add_option("--rpm", device.rotation_rpm, "Rotation speed (SCAN)");
  app.add_option("--seed", device.seed, "Random seed (motor phase, jitter, corruption)");
  std::string scenario;
  std::string lcm_url;
  std::string joint_channel = "SELFCAL_JOINT_STATE";
  app.add_option("--scenario", scenario,
                 "Scenario file: serve ranges cast in its scene from its robot's flange");
  app.add_option("--lcm-url", lcm_url, "LCM URL for the joint states (--scenario)");
  app.add_option("--joint-channel", joint_channel, "Channel of selfcal.joint_state_t");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }
  spdlog::set_default_logger(spdlog::stderr_color_mt("selfcal-sim-scip"));
  if (latency_ms < 0 || jitter_ms < 0 || device.rotation_rpm <= 0) {
    std::cerr << "error: latency, jitter and rpm must be positive\n";
    return 2;
  }
  device.latency_us = latency_ms * 1000;
  device.latency_jitter_us = jitter_ms * 1000;
  server.transport = pty ? SimServerOptions::Transport::kPty : SimServerOptions::Transport::kTcp;
  spdlog::info(
      "config: transport={} address={} port={} link={} drift_ppm={} offset_ms={} "
      "latency_ms={} jitter_ms={} motor_speed_error={} serial_baud={} model={} rpm={} "
      "seed={} scenario={} lcm_url={} joint_channel={}",
      pty ? "pty" : "tcp", server.address, server.port, server.pty_link, device.clock_drift_ppm,
      device.clock_offset_ms, latency_ms, jitter_ms, device.motor_speed_error, device.serial_baud,
      device.model, device.rotation_rpm, device.seed, scenario, lcm_url, joint_channel);
  std::shared_ptr<RangeSource> source;
#ifdef SELFCAL_SIM_SCIP_WITH_SCENE
  std::unique_ptr<selfcal::Bus> bus;
#endif
  std::thread bus_thread;
  std::atomic<bool> bus_stop{false};
  std::int64_t rejected_states = 0;
  if (!scenario.empty()) {
#ifdef SELFCAL_SIM_SCIP_WITH_SCENE
    auto scene = SceneRangeSource::Create(scenario);
    if (!scene) {
      std::cerr << "error: " << scene.error().message << "\n";
      return 2;
    }
    auto opened = selfcal::OpenLcmBus(lcm_url);
    if (!opened) {
      std::cerr << "error: " << opened.error().message << "\n";
      return 1;
    }
    bus = std::move(*opened);
    std::shared_ptr<SceneRangeSource> scene_source = std::move(*scene);
    FeedJointStates(*bus, joint_channel, *scene_source, &rejected_states);
    source = scene_source;
    spdlog::info("scenario: {} ({} joints), joint states on {} at {}", scenario,
                 scene_source->joint_names().size(), joint_channel, bus->url());
    bus_thread = std::thread([&] {
      while (!bus_stop.load()) (void)bus->HandleOnce(std::chrono::milliseconds(50));
    });
#else
    std::cerr << "error: --scenario needs core/sim, which this build lacks\n";
    return 2;
#endif
  }
  auto sim = SimServer::Start(device, server, source);
  if (!sim) {
    std::cerr << "error: " << sim.error().message << "\n";
    return 1;
  }
  if (pty) {
    std::cout << "pty " << (*sim)->pty_path() << std::endl;
  } else {
    std::cout << "port " << (*sim)->port() << std::endl;
  }
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  std::string line;
  bool stdin_open = true;
  while (!g_stop.load()) {
    if (!stdin_open) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      continue;
    }
    pollfd p{STDIN_FILENO, POLLIN, 0};
    if (poll(&p, 1, 100) <= 0) continue;
    if (!std::getline(std::cin, line)) {
      stdin_open = false;  // keep serving until a signal
      continue;
    }
    std::istringstream words(line);
    std::string verb;
    words >> verb;
    double value = 0;
    if (verb == "quit") break;
    if (verb == "junk") {
      std::string rest;
      std::getline(words, rest);
      (*sim)->InjectJunk(rest.empty() ? "junk" : rest.substr(1));
    } else if (verb == "disconnect" && words >> value) {
      (*sim)->Disconnect(value);
    } else if (verb == "reboot" && words >> value) {
      (*sim)->Reboot(value);
    } else if (verb == "corrupt" && words >> value) {
      (*sim)->CorruptNextScans(static_cast<int>(value));
    } else if (verb == "stall" && words >> value) {
      (*sim)->Stall(value);
    } else if (!verb.empty()) {
      spdlog::warn(
          "unknown fault '{}' (disconnect S | reboot S | corrupt N | stall S | junk "
          "TEXT | quit)",
          line);
      continue;
    }
    spdlog::info("fault: {}", line);
  }
  (*sim)->Stop();
  bus_stop.store(true);
  if (bus_thread.joinable()) bus_thread.join();
  if (rejected_states > 0) spdlog::warn("{} joint states rejected", rejected_states);
  return 0;
}
