// selfcal-hokuyo: streams a Hokuyo (UTM-30LX and other SCIP 2.0 sensors) to LCM as
// selfcal.range_scan_t, with per-ray host timestamps. One process per sensor.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <iostream>

#include "drivers/hokuyo/config.h"
#include "drivers/hokuyo/driver.h"
#include "drivers/hokuyo/publisher.h"
#include "drivers/hokuyo/usb_discovery.h"

namespace {

std::atomic<bool> g_stop{false};
void OnSignal(int) { g_stop.store(true); }

}  // namespace

int main(int argc, char** argv) {
  using selfcal::hokuyo::ProcessConfig;
  CLI::App app{
      "selfcal-hokuyo: Hokuyo SCIP 2.0 driver (USB, RS-232, Ethernet). Publishes\n"
      "selfcal.range_scan_t with per-ray host timestamps; reconnects on its own."};
  std::string config_file;
  ProcessConfig flags = selfcal::hokuyo::DefaultProcessConfig();
  std::string scan_type = "MD";
  bool list_usb = false;
  bool verbose = false;
  app.add_option("-c,--config", config_file, "YAML configuration file (flags override it)");
  auto* device = app.add_option("--device", flags.driver.device, "Serial device (/dev/ttyACM0)");
  auto* host = app.add_option("--host", flags.driver.host, "Sensor address (Ethernet)");
  auto* port = app.add_option("--port", flags.driver.port, "Sensor TCP port (default 10940)");
  auto* usb = app.add_flag("--usb", flags.driver.usb, "Use the first Hokuyo found on USB");
  auto* baud = app.add_option("--baud", flags.driver.baud, "Serial rate to open at (0: detect)");
  auto* target = app.add_option("--target-baud", flags.driver.target_baud,
                                "Serial rate to switch to with SS (0: keep)");
  auto* type = app.add_option("--scan-type", scan_type, "MD (ranges) or ME (with intensities)");
  auto* start = app.add_option("--start-step", flags.driver.start_step, "First step (-1: AMIN)");
  auto* end = app.add_option("--end-step", flags.driver.end_step, "Last step (-1: AMAX)");
  auto* cluster = app.add_option("--cluster", flags.driver.cluster, "Steps per value (1..99)");
  auto* skip = app.add_option("--skip", flags.driver.skip, "Rotations skipped between scans");
  auto* sync = app.add_option("--sync-interval", flags.driver.sync_interval_s,
                              "Seconds between TM1 exchanges while streaming");
  auto* stall = app.add_option("--stall-timeout", flags.driver.stall_timeout_s,
                               "Seconds without a scan before reconnecting");
  auto* backoff = app.add_option("--backoff-max", flags.driver.backoff_max_s,
                                 "Longest wait between reconnection attempts [s]");
  auto* channel = app.add_option("--channel", flags.channel, "LCM channel");
  auto* url = app.add_option("--lcm-url", flags.lcm_url, "LCM URL (default: LCM's default)");
  app.add_flag("--list-usb", list_usb, "List attached Hokuyos (USB vendor 0x15d1) and exit");
  app.add_flag("-v,--verbose", verbose, "Log debug messages");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }
  spdlog::set_default_logger(spdlog::stderr_color_mt("selfcal-hokuyo"));
  spdlog::set_level(verbose ? spdlog::level::debug : spdlog::level::info);

  if (list_usb) {
    auto devices = selfcal::hokuyo::ListHokuyoUsb();
    if (!devices) {
      std::cerr << "error: " << devices.error().message << "\n";
      return 1;
    }
    for (const auto& d : *devices) {
      std::cout << "bus " << d.bus << " address " << d.address << " port " << d.port_path
                << " product 0x" << std::hex << d.product_id << std::dec << " tty "
                << (d.tty.empty() ? "-" : d.tty) << "\n";
    }
    std::cout << devices->size() << " Hokuyo(s) on USB\n";
    return 0;
  }

  ProcessConfig config = selfcal::hokuyo::DefaultProcessConfig();
  if (!config_file.empty()) {
    if (auto status = selfcal::hokuyo::ReadProcessConfig(config_file, config); !status) {
      std::cerr << "error: " << status.error().message << "\n";
      return 2;
    }
  }
  // Flags given on the command line override the file.
  auto& d = config.driver;
  const auto& f = flags.driver;
  if (device->count()) d.device = f.device;
  if (host->count()) d.host = f.host;
  if (port->count()) d.port = f.port;
  if (usb->count()) d.usb = f.usb;
  if (baud->count()) d.baud = f.baud;
  if (target->count()) d.target_baud = f.target_baud;
  if (type->count()) {
    auto parsed = selfcal::hokuyo::ParseScanType(scan_type);
    if (!parsed) {
      std::cerr << "error: " << parsed.error().message << "\n";
      return 2;
    }
    d.scan_type = *parsed;
  }
  if (start->count()) d.start_step = f.start_step;
  if (end->count()) d.end_step = f.end_step;
  if (cluster->count()) d.cluster = f.cluster;
  if (skip->count()) d.skip = f.skip;
  if (sync->count()) d.sync_interval_s = f.sync_interval_s;
  if (stall->count()) d.stall_timeout_s = f.stall_timeout_s;
  if (backoff->count()) d.backoff_max_s = f.backoff_max_s;
  if (channel->count()) config.channel = flags.channel;
  if (url->count()) config.lcm_url = flags.lcm_url;
  if (auto status = selfcal::hokuyo::HokuyoDriver::Validate(d); !status) {
    std::cerr << "error: " << status.error().message << "\n";
    return 2;
  }

  spdlog::info(
      "config: device={} host={} port={} usb={} baud={} target_baud={} scan_type={} "
      "start_step={} end_step={} cluster={} skip={} sync_exchanges={} sync_interval_s={} "
      "reply_timeout_s={} stall_timeout_s={} backoff_initial_s={} backoff_max_s={} channel={} "
      "lcm_url={}",
      d.device, d.host, d.port, d.usb, d.baud, d.target_baud, selfcal::scip::Info(d.scan_type).name,
      d.start_step, d.end_step, d.cluster, d.skip, d.sync_exchanges, d.sync_interval_s,
      d.reply_timeout_s, d.stall_timeout_s, d.backoff_initial_s, d.backoff_max_s, config.channel,
      config.lcm_url);

  auto bus = selfcal::OpenLcmBus(config.lcm_url);
  if (!bus) {
    std::cerr << "error: " << bus.error().message << "\n";
    return 1;
  }
  selfcal::hokuyo::ScanPublisher publisher(**bus, config.channel);
  selfcal::hokuyo::HokuyoDriver driver(
      d, [&](const selfcal::hokuyo::RangeScan& scan) { publisher.Submit(scan); },
      [](selfcal::hokuyo::LogLevel level, const std::string& message) {
        switch (level) {
          case selfcal::hokuyo::LogLevel::kDebug:
            spdlog::debug("{}", message);
            break;
          case selfcal::hokuyo::LogLevel::kInfo:
            spdlog::info("{}", message);
            break;
          case selfcal::hokuyo::LogLevel::kWarn:
            spdlog::warn("{}", message);
            break;
          case selfcal::hokuyo::LogLevel::kError:
            spdlog::error("{}", message);
            break;
        }
      });
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  driver.Run(g_stop);
  publisher.Flush();
  const auto& stats = driver.stats();
  spdlog::info(
      "stopped: scans_published={} scans_dropped={} lost_scans={} sessions={} "
      "bus_published={} bus_dropped={}",
      stats.scans_published.load(), stats.scans_dropped.load(), stats.lost_scans.load(),
      stats.sessions.load(), publisher.published(), publisher.dropped());
  return 0;
}
