// `selfcal trigger`: asks selfcald to run a calibration session (a signed START request) and,
// with --wait (the default), follows it to the end.
#include "selfcal/calibration_request_t.hpp"
#include "tools/selfcal/commands.h"
#include "tools/selfcal/daemon_client.h"

namespace selfcal::cli {

void RegisterTrigger(CLI::App& app) {
  auto* command =
      app.add_subcommand("trigger", "Start a calibration session on selfcald (signed request)");
  struct Options {
    DaemonClientOptions client;
    std::string plan;
    std::string by = DefaultRequester();
    bool no_wait = false;
    double session_timeout = 1800;
  };
  auto options = std::make_shared<Options>();
  AddDaemonClientOptions(command, options->client);
  command->add_option("--plan", options->plan, "Scan plan (default: the daemon's default plan)");
  command->add_option("--by", options->by, "Who asks, for the logs and the history");
  command->add_flag("--no-wait", options->no_wait, "Return once the daemon accepted the request");
  command->add_option("--session-timeout", options->session_timeout,
                      "Seconds to follow the session");
  command->callback([options] {
    exit_code = SendRequest(options->client, selfcal::calibration_request_t::START, options->plan,
                            options->by, !options->no_wait, options->session_timeout);
  });
}

}  // namespace selfcal::cli
