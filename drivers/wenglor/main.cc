// selfcal-wenglor: publishes the profiles of a Wenglor weCat3D line scanner (MLSL/MLWL) as
// selfcal.line_profile_t over LCM. The vendor's libEthernetScanner.so is loaded at run time.
#include <spdlog/spdlog.h>

#include "drivers/wenglor/driver_loop.h"
#include "drivers/wenglor/profile_publisher.h"
#include "drivers/wenglor/wenglor_config.h"
#include "drivers/wenglor/wenglor_scanner.h"
#include "protocols/program/program.h"

namespace {

namespace program = selfcal::program;
using selfcal::wenglor::WenglorConfig;

constexpr program::About kAbout{
    "selfcal-wenglor",
    "selfcal-wenglor: publishes the profiles of a Wenglor weCat3D line scanner (MLSL/MLWL)\n"
    "as selfcal.line_profile_t over LCM, through the vendor's libEthernetScanner.so.\n"
    "Settings come from --config (YAML, see config/drivers/wenglor.yaml); flags override it."};

struct Settings {
  WenglorConfig config;
  std::string config_path;
  std::string trigger;  // parsed after the file, so that its error names the flag
  double run_seconds = 0;
  int stats_interval_s = 10;
};

// Every setting of WenglorConfig, in the order of the configuration echo.
void DescribeOptions(program::Program& p, Settings& s) {
  auto& c = s.config;
  p.app()
      .add_option("-c,--config", s.config_path, "YAML settings file (flags override it)")
      ->check(CLI::ExistingFile);
  p.Option("--library", c.library_path, "Path of libEthernetScanner.so");
  p.Option("--ip", c.ip, "Sensor address");
  p.Option("--port", c.port, "Sensor port");
  p.Option("--connect-timeout-ms", c.connect_timeout_ms, "Connection timeout [ms]");
  p.Option("--data-timeout-ms", c.data_timeout_ms,
           "Silence [ms] after which the link counts as lost (internal trigger)");
  p.Option("--reconnect-interval-ms", c.reconnect_interval_ms, "Wait between reconnections");
  p.Option("--poll-interval-us", c.poll_interval_us, "Sleep when the library has no profile");
  p.Option("--exposure-us", c.exposure_time_us, "Exposure time [us], 26..100000");
  p.Option("--line-time-us", c.line_time_us, "Line time [us] for the internal trigger");
  p.app().add_option("--trigger", s.trigger,
                     "Trigger source: internal, sync_in, encoder, software (default internal)");
  p.EchoValue("trigger",
              [&c] { return selfcal::wenglor::kTriggerSourceNames.Name(c.trigger_source); });
  p.Option("--encoder-step", c.encoder_step, "Encoder trigger: steps per profile");
  p.Option("--signal-selection", c.signal_selection, "SetSignalSelection (vendor code)");
  p.Option("--signals-per-column", c.signals_per_column, "Buffer entries per column (1 or 2)");
  p.Option("--max-clock-drift-ppm", c.max_clock_drift_ppm, "Bound on the line clock's drift");
  p.LcmUrlOption(c.lcm_url);
  p.Option("--channel", c.channel, "LCM channel");
  p.Option("--queue-profiles", c.queue_profiles, "Profiles buffered before publishing");
  p.Option("--run-seconds", s.run_seconds, "Stop after this many seconds (0: run until SIGTERM)")
      ->check(program::kNonNegative);
  p.Option("--stats-interval-s", s.stats_interval_s, "Seconds between statistics lines")
      ->check(program::kPositive);
}

// The file under the flags; nothing when the settings are usable, else the exit code.
std::optional<int> Resolve(program::Program& p, Settings& s) {
  if (!s.config_path.empty()) {
    auto read = selfcal::wenglor::ReadWenglorConfig(s.config_path);
    if (!read.ok()) return program::Fail(read.error().message);
    s.config = *read;
    p.ApplyCommandLineAgain();
  }
  if (!s.trigger.empty()) {
    const auto& names = selfcal::wenglor::kTriggerSourceNames;
    const auto source = names.Parse(s.trigger);
    if (!source) {
      return program::Fail("--trigger must be " + names.Listed() + ", not '" + s.trigger + "'");
    }
    s.config.trigger_source = *source;
  }
  if (const auto valid = selfcal::wenglor::ValidateConfig(s.config); !valid.ok()) {
    return program::Fail(valid.error().message);
  }
  return std::nullopt;
}

void Run(selfcal::wenglor::WenglorScanner& scanner, selfcal::Bus& bus, const Settings& s) {
  std::atomic<bool>& stop = program::StopOnSignals();
  selfcal::wenglor::ProfilePublisher publisher(bus, s.config.channel, s.config.queue_profiles,
                                               scanner.capacity());
  const auto start = std::chrono::steady_clock::now();
  const auto interval = std::chrono::seconds(s.stats_interval_s);
  auto next_stats = start + interval;
  auto log_stats = [&] {
    const auto& st = scanner.stats();
    const auto pub = publisher.stats();
    spdlog::info(
        "stats profiles={} published={} lost={} gaps={} restarts={} duplicates={} "
        "invalid_lin_data={} invalid_buffer={} unknown_codes={} connects={} "
        "link_losses={} queue_dropped={} publish_errors={} library_fifo_percent={}",
        st.profiles, pub.published, st.lost_profiles, st.counter_gaps, st.counter_restarts,
        st.duplicates, st.invalid_lin_data, st.invalid_buffer, st.unknown_codes, st.connects,
        st.link_losses, pub.dropped_queue_full, pub.publish_errors, scanner.FifoFillPercent());
  };
  auto tick = [&] {
    const auto now = std::chrono::steady_clock::now();
    if (now >= next_stats) {
      next_stats += interval;
      log_stats();
    }
    if (s.run_seconds > 0 && now - start >= std::chrono::duration<double>(s.run_seconds)) {
      stop.store(true);
    }
  };
  selfcal::wenglor::RunScanner(
      scanner, stop, [&](const selfcal::wenglor::Profile& p) { publisher.Push(p); }, tick,
      std::chrono::milliseconds(100));
  publisher.Stop();
  log_stats();
}

// Everything after the command line: read the file, open the scanner and the bus, echo, run.
int Start(program::Program& program, Settings& s) {
  if (auto exit = Resolve(program, s)) return *exit;
  program.LogConfiguration();
  auto scanner = selfcal::wenglor::WenglorScanner::Create(s.config, program::Logger());
  if (!scanner.ok()) return program::Fail(scanner.error().message);
  spdlog::info("library {} version '{}'", s.config.library_path, (*scanner)->library_version());
  auto bus = program.OpenBus(s.config.lcm_url);
  if (!bus.ok()) return program::Fail(bus.error().message);
  Run(**scanner, **bus, s);
  return program::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return program::Main<Settings>(argc, argv, kAbout, DescribeOptions, Start);
}
