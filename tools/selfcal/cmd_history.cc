// `selfcal history`: the sessions selfcald ran, newest first, from its SQLite history, and
// `selfcal history export`, which copies them into PostgreSQL (history_export.h).
#include <cstdio>
#include <ctime>

#include "daemon/config.h"
#include "daemon/history.h"
#include "tools/selfcal/cli_util.h"
#include "tools/selfcal/commands.h"
#include "tools/selfcal/daemon_client.h"
#include "tools/selfcal/history_export.h"

namespace selfcal::cli {

namespace {

struct HistoryOptions {
  std::string config = daemon::InstalledDaemonConfig();
  std::string storage;
};

void AddStorageOptions(CLI::App* command, HistoryOptions& options) {
  AddDaemonConfigOption(command, options.config, "for its storage folder and robot id");
  command->add_option("--storage", options.storage,
                      "The daemon's storage folder (overrides --config)");
}

// The storage folder and the robot id: from the options, else from the daemon's configuration.
struct Storage {
  std::string folder, robot_id;
};
Expected<Storage> StorageOf(const HistoryOptions& options, const std::string& robot_id,
                            bool needs_robot_id) {
  Storage storage{options.storage, robot_id};
  if (!storage.folder.empty() && (!storage.robot_id.empty() || !needs_robot_id)) return storage;
  auto config = daemon::ReadDaemonConfig(options.config);
  if (!config) {
    return Error{config.error().message +
                 (needs_robot_id ? " (or give --storage and --robot-id)" : " (or give --storage)")};
  }
  if (storage.folder.empty()) storage.folder = config->storage.folder;
  if (storage.robot_id.empty()) storage.robot_id = config->robot_id;
  return storage;
}

void RegisterExport(CLI::App& history) {
  auto* command = history.add_subcommand(
      "export", "Copy the sessions, results and parameter values into PostgreSQL");
  struct Options : HistoryOptions {
    std::string to, robot_id;
    bool schema = false;
  };
  auto options = std::make_shared<Options>();
  command->add_option("--to", options->to,
                      "The database: a libpq connection string or URI, e.g. "
                      "postgresql://fleet@db.example/selfcal (passwords belong in ~/.pgpass)");
  command->add_flag("--schema", options->schema,
                    "Print the tables the export creates (SQL) and exit, e.g. for a database "
                    "administrator who creates them with their own owner and grants");
  AddStorageOptions(command, *options);
  command
      ->add_option("--robot-id", options->robot_id,
                   "The robot the rows belong to (default: the configuration's robot_id)")
      ->check(CLI::Validator(
          [](const std::string& id) {
            return daemon::IsValidRobotId(id) ? ""
                                              : std::string("robot id ") + daemon::kRobotIdRule;
          },
          "ROBOT_ID"));
  command->callback([options] {
    if (options->schema) {
      std::fputs(FleetSchemaSql(), stdout);
      return;
    }
    if (options->to.empty()) {
      exit_code = Fail("--to is required: the database to export to (see --help)");
      return;
    }
    auto storage = StorageOf(*options, options->robot_id, /*needs_robot_id=*/true);
    if (!storage) {
      exit_code = Fail(storage.error().message);
      return;
    }
    auto summary = ExportHistory(storage->folder, storage->robot_id, options->to);
    if (!summary) {
      exit_code = Fail(summary.error().message);
      return;
    }
    std::printf(
        "robot %s: %d sessions added, %d updated, %d unchanged; %d results and %d parameter "
        "values added\n",
        storage->robot_id.c_str(), summary->sessions_added, summary->sessions_updated,
        summary->sessions_unchanged, summary->results_added, summary->parameters_added);
    if (summary->models_missing > 0) {
      std::printf(
          "note: %d accepted sessions have no model in the storage any more: their results "
          "were not exported\n",
          summary->models_missing);
    }
  });
}

}  // namespace

void RegisterHistory(CLI::App& app) {
  auto* command = app.add_subcommand("history", "List selfcald's sessions and results");
  struct Options : HistoryOptions {
    int limit = 20;
  };
  auto options = std::make_shared<Options>();
  AddStorageOptions(command, *options);
  command->add_option("-n,--limit", options->limit, "Sessions to list")->check(CLI::PositiveNumber);
  RegisterExport(*command);
  command->callback([command, options] {
    if (!command->get_subcommands().empty()) return;  // `history export` did the work
    auto storage = StorageOf(*options, "", /*needs_robot_id=*/false);
    if (!storage) {
      exit_code = Fail(storage.error().message);
      return;
    }
    auto history = daemon::History::Open(storage->folder + "/history.sqlite", /*read_only=*/true);
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
      if (!s.change.empty()) std::printf("%-26s what changed: %s\n", "", s.change.c_str());
    }
  });
}

}  // namespace selfcal::cli
