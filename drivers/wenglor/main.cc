// selfcal-wenglor: publishes the profiles of a Wenglor weCat3D line scanner (MLSL/MLWL) as
// selfcal.line_profile_t over LCM. The vendor's libEthernetScanner.so is loaded at run time.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <iostream>

#include "drivers/wenglor/driver_loop.h"
#include "drivers/wenglor/profile_publisher.h"
#include "drivers/wenglor/wenglor_config.h"
#include "drivers/wenglor/wenglor_scanner.h"
#include "protocols/bus/bus.h"

namespace {

std::atomic<bool> stop_requested{false};

void OnSignal(int /*signal*/) { stop_requested.store(true); }

void LogConfig(const selfcal::wenglor::WenglorConfig& c) {
  spdlog::info("config library_path={}", c.library_path);
  spdlog::info("config ip={} port={}", c.ip, c.port);
  spdlog::info(
      "config connect_timeout_ms={} data_timeout_ms={} reconnect_interval_ms={} "
      "poll_interval_us={}",
      c.connect_timeout_ms, c.data_timeout_ms, c.reconnect_interval_ms, c.poll_interval_us);
  spdlog::info(
      "config exposure_time_us={} line_time_us={} trigger_source={} encoder_step={} "
      "signal_selection={} signals_per_column={}",
      c.exposure_time_us, c.line_time_us, TriggerSourceName(c.trigger_source), c.encoder_step,
      c.signal_selection, c.signals_per_column);
  spdlog::info("config max_clock_drift_ppm={} lcm_url={} channel={} queue_profiles={}",
               c.max_clock_drift_ppm, c.lcm_url, c.channel, c.queue_profiles);
}

int Fail(const std::string& reason) {
  std::cerr << "error: " << reason << "\n";
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  using selfcal::wenglor::WenglorConfig;
  CLI::App app{
      "selfcal-wenglor: publishes the profiles of a Wenglor weCat3D line scanner (MLSL/MLWL)\n"
      "as selfcal.line_profile_t over LCM, through the vendor's libEthernetScanner.so.\n"
      "Settings come from --config (YAML, see config/drivers/wenglor.yaml); flags override it."};
  std::string config_path;
  std::string library_path, ip, port, trigger, lcm_url, channel;
  int exposure_time_us = 0, line_time_us = 0, connect_timeout_ms = 0, data_timeout_ms = 0;
  int reconnect_interval_ms = 0;
  double run_seconds = 0;
  int stats_interval_s = 10;
  bool verbose = false;
  app.add_option("-c,--config", config_path, "YAML settings file")->check(CLI::ExistingFile);
  app.add_option("--library", library_path, "Path of libEthernetScanner.so");
  app.add_option("--ip", ip, "Sensor address (default 192.168.100.1)");
  app.add_option("--port", port, "Sensor port (default 32001)");
  app.add_option("--exposure-us", exposure_time_us, "Exposure time [us], 26..100000");
  app.add_option("--line-time-us", line_time_us, "Line time [us] for the internal trigger");
  app.add_option("--trigger", trigger, "Trigger source: internal, sync_in, encoder, software");
  app.add_option("--connect-timeout-ms", connect_timeout_ms, "Connection timeout [ms]");
  app.add_option("--data-timeout-ms", data_timeout_ms,
                 "Silence [ms] after which the link counts as lost (internal trigger)");
  app.add_option("--reconnect-interval-ms", reconnect_interval_ms, "Wait between reconnections");
  app.add_option("--lcm-url", lcm_url, "LCM URL (default udpm://239.255.76.67:7667?ttl=0)");
  app.add_option("--channel", channel, "LCM channel (default SELFCAL_LINE_PROFILE)");
  app.add_option("--run-seconds", run_seconds,
                 "Stop after this many seconds (0: run until SIGTERM)");
  app.add_option("--stats-interval-s", stats_interval_s, "Seconds between statistics lines")
      ->check(CLI::PositiveNumber);
  app.add_flag("-v,--verbose", verbose, "Log debug messages");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }
  spdlog::set_default_logger(spdlog::stderr_color_mt("selfcal-wenglor"));
  spdlog::set_level(verbose ? spdlog::level::debug : spdlog::level::info);

  WenglorConfig config;
  if (!config_path.empty()) {
    auto read = selfcal::wenglor::ReadWenglorConfig(config_path);
    if (!read.ok()) return Fail(read.error().message);
    config = *read;
  }
  if (!library_path.empty()) config.library_path = library_path;
  if (!ip.empty()) config.ip = ip;
  if (!port.empty()) config.port = port;
  if (exposure_time_us != 0) config.exposure_time_us = exposure_time_us;
  if (line_time_us != 0) config.line_time_us = line_time_us;
  if (connect_timeout_ms != 0) config.connect_timeout_ms = connect_timeout_ms;
  if (data_timeout_ms != 0) config.data_timeout_ms = data_timeout_ms;
  if (reconnect_interval_ms != 0) config.reconnect_interval_ms = reconnect_interval_ms;
  if (!trigger.empty()) {
    auto source = selfcal::wenglor::ParseTriggerSource(trigger);
    if (!source.ok()) return Fail("--trigger " + source.error().message);
    config.trigger_source = *source;
  }
  if (!lcm_url.empty()) config.lcm_url = lcm_url;
  if (!channel.empty()) config.channel = channel;
  if (run_seconds < 0) return Fail("--run-seconds must not be negative");
  if (const auto valid = selfcal::wenglor::ValidateConfig(config); !valid.ok()) {
    return Fail(valid.error().message);
  }
  LogConfig(config);

  auto scanner = selfcal::wenglor::WenglorScanner::Create(
      config, [](selfcal::wenglor::LogLevel level, const std::string& message) {
        switch (level) {
          case selfcal::wenglor::LogLevel::kDebug:
            spdlog::debug("{}", message);
            break;
          case selfcal::wenglor::LogLevel::kInfo:
            spdlog::info("{}", message);
            break;
          case selfcal::wenglor::LogLevel::kWarning:
            spdlog::warn("{}", message);
            break;
          case selfcal::wenglor::LogLevel::kError:
            spdlog::error("{}", message);
            break;
        }
      });
  if (!scanner.ok()) return Fail(scanner.error().message);
  spdlog::info("library {} version '{}'", config.library_path, (*scanner)->library_version());
  auto bus = selfcal::OpenLcmBus(config.lcm_url);
  if (!bus.ok()) return Fail(bus.error().message);

  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  selfcal::wenglor::ProfilePublisher publisher(**bus, config.channel, config.queue_profiles,
                                               (*scanner)->capacity());
  const auto start = std::chrono::steady_clock::now();
  auto next_stats = start + std::chrono::seconds(stats_interval_s);
  auto& s = **scanner;
  auto log_stats = [&] {
    const auto& st = s.stats();
    const auto pub = publisher.stats();
    spdlog::info(
        "stats profiles={} published={} lost={} gaps={} restarts={} duplicates={} "
        "invalid_lin_data={} invalid_buffer={} unknown_codes={} connects={} "
        "link_losses={} queue_dropped={} publish_errors={} library_fifo_percent={}",
        st.profiles, pub.published, st.lost_profiles, st.counter_gaps, st.counter_restarts,
        st.duplicates, st.invalid_lin_data, st.invalid_buffer, st.unknown_codes, st.connects,
        st.link_losses, pub.dropped_queue_full, pub.publish_errors, s.FifoFillPercent());
  };
  selfcal::wenglor::RunScanner(
      s, stop_requested, [&](const selfcal::wenglor::Profile& p) { publisher.Push(p); },
      [&] {
        const auto now = std::chrono::steady_clock::now();
        if (now >= next_stats) {
          next_stats += std::chrono::seconds(stats_interval_s);
          log_stats();
        }
        if (run_seconds > 0 && std::chrono::steady_clock::now() - start >=
                                   std::chrono::duration<double>(run_seconds)) {
          stop_requested.store(true);
        }
      },
      std::chrono::milliseconds(100));
  publisher.Stop();
  log_stats();
  return 0;
}
