// `selfcal history`: the sessions selfcald ran, newest first, from its SQLite history.
#include <cstdio>
#include <ctime>

#include "daemon/config.h"
#include "daemon/history.h"
#include "tools/selfcal/cli_util.h"
#include "tools/selfcal/commands.h"

namespace selfcal::cli {

void RegisterHistory(CLI::App& app) {
  auto* command = app.add_subcommand("history", "List selfcald's sessions and results");
  struct Options {
    std::string config = daemon::InstalledDaemonConfig();
    std::string storage;
    int limit = 20;
  };
  auto options = std::make_shared<Options>();
  command
      ->add_option("-c,--config", options->config,
                   "The daemon's configuration (for its storage folder)")
      ->capture_default_str()
      ->check(kFileNotFolder);
  command->add_option("--storage", options->storage,
                      "The daemon's storage folder (overrides --config)");
  command->add_option("-n,--limit", options->limit, "Sessions to list")->check(CLI::PositiveNumber);
  command->callback([options] {
    std::string storage = options->storage;
    if (storage.empty()) {
      auto config = daemon::ReadDaemonConfig(options->config);
      if (!config) {
        exit_code = Fail(config.error().message);
        return;
      }
      storage = config->storage.folder;
    }
    auto history = daemon::History::Open(storage + "/history.sqlite", /*read_only=*/true);
    if (!history) {
      exit_code = Fail(history.error().message);
      return;
    }
    auto sessions = (*history)->Sessions(options->limit);
    if (!sessions) {
      exit_code = Fail(sessions.error().message);
      return;
    }
    std::printf("%-26s %-20s %-10s %-12s %10s %10s  %s\n", "session", "started (UTC)", "plan",
                "state", "rms before", "rms after", "reason");
    for (const auto& s : *sessions) {
      const std::time_t seconds = static_cast<std::time_t>(s.started_utime / 1000000);
      std::tm utc{};
      gmtime_r(&seconds, &utc);
      char when[32];
      std::strftime(when, sizeof(when), "%Y-%m-%d %H:%M:%S", &utc);
      char before[32] = "-", after[32] = "-";
      if (s.rms_before >= 0) std::snprintf(before, sizeof(before), "%.3f mm", s.rms_before * 1e3);
      if (s.rms_after >= 0) std::snprintf(after, sizeof(after), "%.3f mm", s.rms_after * 1e3);
      std::printf("%-26s %-20s %-10s %-12s %10s %10s  %s\n", s.id.c_str(), when, s.plan.c_str(),
                  s.state.c_str(), before, after, s.reason.c_str());
    }
  });
}

}  // namespace selfcal::cli
