// `selfcal trigger`: asks selfcald to run a calibration session (a signed START request) and,
// with --wait (the default), follows it to the end.
#include "daemon/config.h"
#include "daemon/plan.h"
#include "selfcal/calibration_request_t.hpp"
#include "tools/selfcal/cli_util.h"
#include "tools/selfcal/commands.h"
#include "tools/selfcal/daemon_client.h"

namespace selfcal::cli {
namespace {

// The plan a `--mode` asks for, from the daemon's configuration: a session's mode is its plan's
// (`mode:` in the plan file, docs/daemon.md "Quick remastering"), so the signed request names a
// plan as ever. `--mode remaster` without --plan takes the configuration's one remaster plan;
// with --plan, that plan must be of the mode asked for. Empty `mode`: `plan` as given.
Expected<std::string> PlanForMode(const std::string& config_path, const std::string& mode,
                                  const std::string& plan) {
  if (mode.empty()) return plan;
  if (mode != "full" && mode != "remaster") {
    return Error{"--mode must be full or remaster, not '" + mode + "'"};
  }
  const auto config = daemon::ReadDaemonConfig(config_path);
  if (!config) return config.error();
  const std::string wanted = plan.empty() && mode == "full" ? config->default_plan : plan;
  std::vector<std::string> found;
  for (const auto& [name, path] : config->plans) {
    if (!wanted.empty() && name != wanted) continue;
    const auto read = daemon::ReadScanPlan(path);
    if (!read) return read.error();
    if (daemon::PlanModeName(read->mode) == mode) {
      found.push_back(name);
    } else if (!wanted.empty()) {
      return Error{"plan " + name + " (" + path + ") is a " + daemon::PlanModeName(read->mode) +
                   " plan, not a " + mode + " one"};
    }
  }
  if (!wanted.empty() && found.empty()) {
    return Error{"plan " + wanted + " is not in the plans of " + config_path};
  }
  if (found.empty()) {
    return Error{config_path +
                 " has no remaster plan (a plan file with 'mode: remaster' under "
                 "plans:; `selfcal daemon-plan --mode remaster` writes one)"};
  }
  if (found.size() > 1) {
    std::string names;
    for (const auto& name : found) names += (names.empty() ? "" : ", ") + name;
    return Error{config_path + " has several remaster plans (" + names + "): name one with --plan"};
  }
  return found.front();
}

}  // namespace

void RegisterTrigger(CLI::App& app) {
  auto* command =
      app.add_subcommand("trigger", "Start a calibration session on selfcald (signed request)");
  struct Options {
    DaemonClientOptions client;
    std::string plan;
    std::string mode;
    std::string by = DefaultRequester();
    bool no_wait = false;
    double session_timeout = 1800;
  };
  auto options = std::make_shared<Options>();
  AddDaemonClientOptions(command, options->client);
  command->add_option("--plan", options->plan, "Scan plan (default: the daemon's default plan)");
  command->add_option("--mode", options->mode,
                      "full or remaster: checks that the plan is of that mode; remaster without "
                      "--plan takes the configuration's remaster plan (a quick remastering: only "
                      "the joints' zero offsets and the sensor mount)");
  command->add_option("--by", options->by, "Who asks, for the logs and the history");
  command->add_flag("--no-wait", options->no_wait, "Return once the daemon accepted the request");
  command->add_option("--session-timeout", options->session_timeout,
                      "Seconds to follow the session");
  command->callback([options] {
    const auto plan = PlanForMode(options->client.config, options->mode, options->plan);
    if (!plan) {
      exit_code = Fail(plan.error().message);
      return;
    }
    exit_code = SendRequest(options->client, selfcal::calibration_request_t::START, *plan,
                            options->by, !options->no_wait, options->session_timeout);
  });
}

}  // namespace selfcal::cli
