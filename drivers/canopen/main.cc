// selfcal-canopen: joint states of a CANopen (CiA 402) arm over SocketCAN (canopen_driver.h).
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <iostream>

#include "drivers/canopen/canopen_driver.h"

namespace {
volatile std::sig_atomic_t stop_requested = 0;
void OnSignal(int) { stop_requested = 1; }
}  // namespace

int main(int argc, char** argv) {
  using namespace selfcal;
  using namespace selfcal::canopen;
  CLI::App app{
      "selfcal-canopen: joint states of a CANopen (CiA 402) arm over SocketCAN. Starts "
      "the nodes (NMT), watches heartbeats, produces or follows SYNC, reads the position "
      "actual value from SYNC-triggered TPDOs and publishes selfcal.joint_state_t with "
      "SYNC-based host timestamps."};
  CanopenDriverOptions options;
  std::string config_path = "/etc/selfcal/drivers/canopen.yaml";
  std::string lcm_url;
  double duration_s = 0;
  app.add_option("--config", config_path, "Driver configuration (YAML)")->capture_default_str();
  app.add_option("--lcm_url", lcm_url, "LCM URL (empty: LCM_DEFAULT_URL or liblcm's default)");
  app.add_option("--joint_state_channel", options.joint_state_channel)->capture_default_str();
  app.add_option("--status_channel", options.status_channel)->capture_default_str();
  app.add_option("--clock_settle", options.clock.settle_s,
                 "Seconds of SYNCs before joint states are published")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--clock_settle_samples", options.clock.settle_samples,
                 "SYNCs before joint states are published")
      ->capture_default_str();
  app.add_option("--duration", duration_s, "Exit after this many seconds (0: until SIGINT)")
      ->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }
  spdlog::set_default_logger(spdlog::stderr_color_mt("selfcal-canopen"));
  auto config = ReadCanopenConfig(config_path);
  if (!config.ok()) {
    std::cerr << "error: " << config.error().message << "\n";
    return 1;
  }
  options.config = *config;
  if (options.clock.settle_samples < 2) options.clock.settle_samples = 2;
  options.clock.bins = static_cast<int>(std::min<std::size_t>(8, options.clock.settle_samples));
  auto bus = OpenLcmBus(lcm_url);
  if (!bus.ok()) {
    std::cerr << "error: " << bus.error().message << "\n";
    return 1;
  }
  auto socket = CanSocket::OpenSocketCan(options.config.interface);
  if (!socket.ok()) {
    std::cerr << "error: " << socket.error().message << "\n";
    return 1;
  }
  spdlog::info(
      "config={} interface={} joints={} produce_sync={} sync_period={} "
      "sync_counter_overflow={} start_nodes={} heartbeat_timeout={} lcm_url={} "
      "joint_state_channel={} status_channel={} clock_settle={} clock_settle_samples={}",
      config_path, options.config.interface, options.config.joints.size(),
      options.config.produce_sync, options.config.sync_period_s,
      options.config.sync_counter_overflow, options.config.start_nodes,
      options.config.heartbeat_timeout_s, (*bus)->url(), options.joint_state_channel,
      options.status_channel, options.clock.settle_s, options.clock.settle_samples);
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  CanopenDriver driver(options, std::move(*socket), **bus);
  const auto start = std::chrono::steady_clock::now();
  while (!stop_requested) {
    if (auto s = driver.SpinOnce(std::chrono::microseconds(500)); !s.ok()) {
      std::cerr << "error: " << s.error().message << "\n";
      return 1;
    }
    if (duration_s > 0 &&
        std::chrono::steady_clock::now() - start > std::chrono::duration<double>(duration_s)) {
      break;
    }
  }
  spdlog::info("stopping: {} SYNCs, {} incomplete, {} bad frames, {} joint states",
               driver.source().syncs() + 1, driver.source().incomplete_syncs(),
               driver.source().bad_frames(), driver.published());
  return 0;
}
