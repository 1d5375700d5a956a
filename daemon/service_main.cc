#include "daemon/service_main.h"

#include <malloc.h>
#include <spdlog/spdlog.h>
#include <systemd/sd-daemon.h>

#include <csignal>
#include <iostream>

#include "daemon/auth.h"
#include "daemon/config.h"
#include "daemon/daemon.h"
#include "daemon/installation_check.h"
#include "daemon/urdf_exporter.h"
#include "protocols/program/program.h"

namespace selfcal::daemon {

namespace {

// The bus loop until SIGTERM or SIGINT, telling systemd how it goes (READY, WATCHDOG, STATUS).
int Serve(Daemon& daemon) {
  const std::atomic<bool>& stop = program::StopOnSignals();
  std::uint64_t watchdog_us = 0;
  const bool watchdog = sd_watchdog_enabled(0, &watchdog_us) > 0;
  sd_notify(0, "READY=1\nSTATUS=idle");
  spdlog::info("ready{}",
               watchdog ? fmt::format(" (watchdog every {} ms)", watchdog_us / 1000) : "");
  std::int64_t last_ping = 0;
  std::string last_message;
  while (!stop.load()) {
    auto step = daemon.Step(std::chrono::milliseconds(10));
    if (!step && stop.load()) break;  // a signal interrupted the receive
    if (!step) {
      spdlog::error("{}", step.error().message);
      sd_notifyf(0, "STATUS=bus failed: %s", step.error().message.c_str());
      return 1;
    }
    const std::int64_t now = timing::MonotonicNs() / 1000;
    if (watchdog && now - last_ping >= static_cast<std::int64_t>(watchdog_us / 2)) {
      sd_notify(0, "WATCHDOG=1");
      last_ping = now;
    }
    if (daemon.message() != last_message) {
      last_message = daemon.message();
      sd_notifyf(0, "STATUS=%s: %s", StateName(daemon.state()), last_message.c_str());
    }
  }
  sd_notify(0, "STOPPING=1");
  spdlog::info("stopping");
  return 0;
}

// Blocks of 256 KiB and more (a session's recording read back by the engine and the report,
// liblcm's large messages) get mappings of their own, returned when freed. By default glibc raises
// this threshold to the largest block freed so far; the blocks then come from the worker threads'
// arenas, whose freed tops stay resident (malloc_trim leaves them), and the daemon kept 2.4 MB
// more after each session's computation (daemon_flood_bench --signed: 5.1 MB growth, 2.7 MB
// with a fixed threshold).
void ReturnLargeBlocksWhenFreed() { mallopt(M_MMAP_THRESHOLD, 256 * 1024); }

}  // namespace

using program::Fail;

int RunService(int argc, char** argv, const EngineFactory& make_engine) {
  program::Program program("selfcald",
                           "selfcald: the selfcal calibration daemon (configured by daemon.yaml)");
  std::string config_path = InstalledDaemonConfig();
  std::string generate_key;
  std::string key_file;
  bool check_only = false;
  program.Option("-c,--config", config_path, "Daemon configuration file");
  program.Option("--generate-key", generate_key,
                 "Write a new random key (mode 0600) to this file and exit; never overwrites");
  program.Option("--key-file", key_file,
                 "Key file (overrides the configuration's; systemd passes its credential copy)");
  program.Flag("--check", check_only,
               "Read the configuration, key, models and plans and check the storage folder's "
               "permissions, then exit; writes nothing");
  if (auto exit = program.Parse(argc, argv)) return *exit;
  if (!generate_key.empty()) {
    auto status = selfcal::auth::GenerateKeyFile(generate_key);
    if (!status) return Fail(status.error().message);
    std::cout << "wrote a new key to " << generate_key << "\n";
    return 0;
  }
  auto config = selfcal::daemon::ReadDaemonConfig(config_path);
  if (!config) return Fail(config.error().message);
  if (!key_file.empty()) config->key_file = key_file;
  DescribeSettings(program, *config);
  program.LogConfiguration();
  if (check_only) {
    auto report = selfcal::daemon::CheckInstallation(*config);
    if (!report) return Fail(report.error().message);
    std::cout << *report << "configuration, key, storage and plans are fine\n";
    return 0;
  }
  ReturnLargeBlocksWhenFreed();  // before the bus and the engine start threads
  auto bus = program.OpenBus(config->lcm_url);
  if (!bus) return Fail(bus.error().message);
  auto engine = make_engine();
  std::unique_ptr<selfcal::daemon::CalibrationEngine> engine_ptr;
  if (engine) {
    engine_ptr = std::move(engine).value();
  } else {
    spdlog::warn("{}; sessions will record and then fail at calibration", engine.error().message);
  }
  auto daemon = selfcal::daemon::Daemon::Create(
      *config, std::shared_ptr<selfcal::Bus>(std::move(bus).value()), std::move(engine_ptr),
      selfcal::daemon::DefaultUrdfExporter());
  if (!daemon) return Fail(daemon.error().message);
  // A full disk with RLIMIT_FSIZE must fail a write, not kill the daemon.
  std::signal(SIGXFSZ, SIG_IGN);

  return Serve(**daemon);
}

}  // namespace selfcal::daemon
