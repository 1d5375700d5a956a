// `selfcal status`: prints selfcald's status (the next one it publishes), or follows it.
#include <cmath>
#include <cstdio>

#include "core/timing/host_clock.h"
#include "daemon/config.h"
#include "daemon/state.h"
#include "protocols/bus/bus.h"
#include "selfcal/calibration_status_t.hpp"
#include "tools/selfcal/cli_util.h"
#include "tools/selfcal/commands.h"
#include "tools/selfcal/daemon_client.h"

namespace selfcal::cli {

void RegisterStatus(CLI::App& app) {
  auto* command = app.add_subcommand("status", "Print the state of selfcald");
  auto client = std::make_shared<DaemonClientOptions>();
  auto follow = std::make_shared<bool>(false);
  AddDaemonClientOptions(command, *client);
  command->add_flag("-f,--follow", *follow, "Keep printing until interrupted");
  command->callback([client, follow] {
    auto config = daemon::ReadDaemonConfig(client->config);
    if (!config) {
      exit_code = Fail(config.error().message);
      return;
    }
    const std::string url = client->lcm_url.empty() ? config->lcm_url : client->lcm_url;
    auto bus = OpenLcmBus(url);
    if (!bus) {
      exit_code = Fail(bus.error().message);
      return;
    }
    bool got = false;
    (*bus)->Subscribe(config->channels.calibration_status, [&](const BusMessage& message) {
      auto status = DecodeLcm<selfcal::calibration_status_t>(message.data, message.channel);
      if (!status) return;
      got = true;
      std::printf("%s%s%s %.0f %% %s\n", daemon::WireStateName(status->state),
                  status->session_id.empty() ? "" : " session ", status->session_id.c_str(),
                  std::floor(100.0 * status->progress), status->message.c_str());
      std::fflush(stdout);
    });
    const std::int64_t start = timing::RealtimeUs();
    while (*follow || !got) {
      if (!got && timing::RealtimeUs() - start > static_cast<std::int64_t>(client->timeout * 1e6)) {
        exit_code = Fail("no status from selfcald on " + config->channels.calibration_status +
                         " within " + std::to_string(client->timeout) + " s");
        return;
      }
      if (auto handled = (*bus)->HandleOnce(std::chrono::milliseconds(200)); !handled) {
        exit_code = Fail(handled.error().message);
        return;
      }
    }
  });
}

}  // namespace selfcal::cli
