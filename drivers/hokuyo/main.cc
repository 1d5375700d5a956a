// selfcal-hokuyo: streams a Hokuyo (UTM-30LX and other SCIP 2.0 sensors) to LCM as
// selfcal.range_scan_t, with per-ray host timestamps. One process per sensor.
#include <spdlog/spdlog.h>

#include <iostream>

#include "drivers/hokuyo/config.h"
#include "drivers/hokuyo/driver.h"
#include "drivers/hokuyo/publisher.h"
#include "drivers/hokuyo/usb_discovery.h"
#include "protocols/program/program.h"

namespace {

namespace program = selfcal::program;
using selfcal::hokuyo::ProcessConfig;

constexpr program::About kAbout{
    "selfcal-hokuyo",
    "selfcal-hokuyo: Hokuyo SCIP 2.0 driver (USB, RS-232, Ethernet). Publishes\n"
    "selfcal.range_scan_t with per-ray host timestamps; reconnects on its own."};

// Every setting of the process, in the order of the configuration echo; the YAML file has the
// same settings (drivers/hokuyo/config.h).
void DescribeOptions(program::Program& p, ProcessConfig& config) {
  auto& d = config.driver;
  p.Option("--device", d.device, "Serial device (/dev/ttyACM0)");
  p.Option("--host", d.host, "Sensor address (Ethernet)");
  p.Option("--port", d.port, "Sensor TCP port");
  p.Flag("--usb", d.usb, "Use the first Hokuyo found on USB");
  p.Option("--baud", d.baud, "Serial rate to open at (0: detect)");
  p.Option("--target-baud", d.target_baud, "Serial rate to switch to with SS (0: keep)");
  p.Choice("--scan-type", d.scan_type,
           {{"MD", selfcal::scip::ScanType::kMD}, {"ME", selfcal::scip::ScanType::kME}},
           "MD (ranges) or ME (with intensities)");
  p.Option("--start-step", d.start_step, "First step (-1: AMIN)");
  p.Option("--end-step", d.end_step, "Last step (-1: AMAX)");
  p.Option("--cluster", d.cluster, "Steps per value (1..99)");
  p.Option("--skip", d.skip, "Rotations skipped between scans");
  p.Option("--sync-exchanges", d.sync_exchanges, "TM1 exchanges before streaming");
  p.Option("--sync-interval", d.sync_interval_s, "Seconds between TM1 exchanges while streaming");
  p.Option("--reply-timeout", d.reply_timeout_s, "Seconds to wait for a reply");
  p.Option("--stall-timeout", d.stall_timeout_s, "Seconds without a scan before reconnecting");
  p.Option("--backoff-initial", d.backoff_initial_s, "First wait between reconnections [s]");
  p.Option("--backoff-max", d.backoff_max_s, "Longest wait between reconnection attempts [s]");
  p.Option("--channel", config.channel, "LCM channel");
  p.LcmUrlOption(config.lcm_url);
}

int ListUsb() {
  auto devices = selfcal::hokuyo::ListHokuyoUsb();
  if (!devices) return program::Fail(devices.error().message);
  for (const auto& d : *devices) {
    std::cout << "bus " << d.bus << " address " << d.address << " port " << d.port_path
              << " product 0x" << std::hex << d.product_id << std::dec << " tty "
              << (d.tty.empty() ? "-" : d.tty) << "\n";
  }
  std::cout << devices->size() << " Hokuyo(s) on USB\n";
  return program::kExitOk;
}

// The process configuration and the options that are not part of it.
struct Settings {
  ProcessConfig config = selfcal::hokuyo::DefaultProcessConfig();
  std::string config_file;
  bool list_usb = false;
};

void DescribeAllOptions(program::Program& p, Settings& s) {
  p.app().add_option("-c,--config", s.config_file, "YAML configuration file (flags override it)");
  DescribeOptions(p, s.config);
  p.app().add_flag("--list-usb", s.list_usb, "List attached Hokuyos (USB vendor 0x15d1) and exit");
}

// Everything after the command line: read the file, validate, open the bus, run.
int Start(program::Program& program, Settings& s) {
  if (s.list_usb) return ListUsb();
  ProcessConfig& config = s.config;
  if (!s.config_file.empty()) {
    config = selfcal::hokuyo::DefaultProcessConfig();
    if (auto status = selfcal::hokuyo::ReadProcessConfig(s.config_file, config); !status) {
      return program::Fail(status.error().message, program::kExitUsage);
    }
    program.ApplyCommandLineAgain();
  }
  if (auto status = selfcal::hokuyo::HokuyoDriver::Validate(config.driver); !status) {
    return program::Fail(status.error().message, program::kExitUsage);
  }
  program.LogConfiguration();

  auto bus = program.OpenBus(config.lcm_url);
  if (!bus) return program::Fail(bus.error().message);
  selfcal::hokuyo::ScanPublisher publisher(**bus, config.channel);
  selfcal::hokuyo::HokuyoDriver driver(
      config.driver, [&](const selfcal::hokuyo::RangeScan& scan) { publisher.Submit(scan); },
      program::Logger());
  driver.Run(program::StopOnSignals());
  publisher.Flush();
  const auto& stats = driver.stats();
  spdlog::info(
      "stopped: scans_published={} scans_dropped={} lost_scans={} sessions={} "
      "bus_published={} bus_dropped={}",
      stats.scans_published.load(), stats.scans_dropped.load(), stats.lost_scans.load(),
      stats.sessions.load(), publisher.published(), publisher.dropped());
  return program::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return program::Main<Settings>(argc, argv, kAbout, DescribeAllOptions, Start);
}
