// `selfcal abort`: stops the running session at once (a signed ABORT request).
#include "selfcal/calibration_request_t.hpp"
#include "tools/selfcal/commands.h"
#include "tools/selfcal/daemon_client.h"

namespace selfcal::cli {

void RegisterAbort(CLI::App& app) {
  auto* command =
      app.add_subcommand("abort", "Abort the running calibration session (signed request)");
  auto client = std::make_shared<DaemonClientOptions>();
  auto by = std::make_shared<std::string>(DefaultRequester());
  AddDaemonClientOptions(command, *client);
  command->add_option("--by", *by, "Who asks, for the logs and the history");
  command->callback([client, by] {
    exit_code = SendRequest(*client, selfcal::calibration_request_t::ABORT, "", *by, false, 0);
  });
}

}  // namespace selfcal::cli
