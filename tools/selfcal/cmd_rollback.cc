// `selfcal rollback`: reinstates the model that was current before the last accepted one
// (a signed ROLLBACK request; the daemon owns the model files).
#include "selfcal/calibration_request_t.hpp"
#include "tools/selfcal/commands.h"
#include "tools/selfcal/daemon_client.h"

namespace selfcal::cli {

void RegisterRollback(CLI::App& app) {
  auto* command =
      app.add_subcommand("rollback", "Reinstate the previous robot model (signed request)");
  auto client = std::make_shared<DaemonClientOptions>();
  auto by = std::make_shared<std::string>(DefaultRequester());
  AddDaemonClientOptions(command, *client);
  command->add_option("--by", *by, "Who asks, for the logs and the history");
  command->callback([client, by] {
    exit_code = SendRequest(*client, selfcal::calibration_request_t::ROLLBACK, "", *by, false, 0);
  });
}

}  // namespace selfcal::cli
