#include "tools/selfcal/daemon_client.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iostream>

#include "core/timing/host_clock.h"
#include "daemon/auth.h"
#include "daemon/config.h"
#include "daemon/state.h"
#include "protocols/bus/bus.h"
#include "selfcal/calibration_request_t.hpp"
#include "selfcal/calibration_result_t.hpp"
#include "selfcal/calibration_status_t.hpp"
#include "tools/selfcal/cli_util.h"
#include "tools/selfcal/commands.h"

namespace selfcal::cli {

void AddDaemonClientOptions(CLI::App* command, DaemonClientOptions& options) {
  command
      ->add_option("-c,--config", options.config,
                   "The daemon's configuration (key file, LCM URL, channels)")
      ->capture_default_str()
      ->check(kFileNotFolder);
  command
      ->add_option("--key", options.key_file,
                   "Key file to sign with (default: the configuration's)")
      ->check(kFileNotFolder);
  command->add_option("--lcm-url", options.lcm_url, "LCM URL (default: the configuration's)");
  command->add_option("--timeout", options.timeout, "Seconds to wait for the daemon's answer");
}

std::string DefaultRequester() {
  const char* user = getenv("USER");
  char host[256] = {};
  gethostname(host, sizeof(host) - 1);
  return std::string(user ? user : "unknown") + "@" + host;
}

int SendRequest(const DaemonClientOptions& options, std::int8_t action, const std::string& plan,
                const std::string& requested_by, bool follow_session, double session_timeout) {
  auto config = daemon::ReadDaemonConfig(options.config);
  if (!config) return Fail(config.error().message);
  const std::string key_path = options.key_file.empty() ? config->key_file : options.key_file;
  auto key = auth::ReadKeyFile(key_path, /*require_private=*/false);
  if (!key) return Fail(key.error().message);
  const std::string url = options.lcm_url.empty() ? config->lcm_url : options.lcm_url;
  auto bus = OpenLcmBus(url);
  if (!bus) return Fail(bus.error().message);

  selfcal::calibration_request_t request;
  request.utime = timing::RealtimeUs();
  request.action = action;
  request.robot_id = config->robot_id;
  request.nonce = daemon::RandomNonce();
  request.plan_name = plan;
  request.requested_by = requested_by;
  daemon::SignRequest(request, *key);

  std::string session_id;
  bool answered = false, refused = false, ended = false;
  std::int8_t final_state = -1;
  std::string last_line;
  std::optional<selfcal::calibration_result_t> result;
  (*bus)->Subscribe(config->channels.calibration_status, [&](const BusMessage& message) {
    auto status = DecodeLcm<selfcal::calibration_status_t>(message.data, message.channel);
    if (!status) return;
    if (!answered) {
      if (status->request_nonce != request.nonce) return;
      answered = true;
      refused = status->message.rfind("refused", 0) == 0;
      std::cout << (refused ? "" : "selfcald: ") << status->message << "\n";
      if (refused) return;
      session_id = status->session_id;
      if (action != selfcal::calibration_request_t::START || session_id.empty()) ended = true;
      return;
    }
    if (status->session_id != session_id) return;
    char line[512];
    std::snprintf(line, sizeof(line), "%-11s %3.0f %%  %s", daemon::WireStateName(status->state),
                  std::floor(100.0 * status->progress / 5.0) * 5.0, status->message.c_str());
    if (line != last_line) {
      std::cout << line << "\n" << std::flush;
      last_line = line;
    }
    if (const auto state = daemon::StateFromWire(status->state);
        state && daemon::IsTerminal(*state)) {
      ended = true;
      final_state = status->state;
    }
  });
  (*bus)->Subscribe(config->channels.calibration_result, [&](const BusMessage& message) {
    auto decoded = DecodeLcm<selfcal::calibration_result_t>(message.data, message.channel);
    if (decoded && decoded->session_id == session_id) result = *decoded;
  });
  auto published = (*bus)->Publish(config->channels.calibration_request, request);
  if (!published) return Fail(published.error().message);

  const std::int64_t start = timing::RealtimeUs();
  while (!answered) {
    if (timing::RealtimeUs() - start > static_cast<std::int64_t>(options.timeout * 1e6)) {
      return Fail("no answer from selfcald on " + config->channels.calibration_status + " within " +
                  std::to_string(options.timeout) + " s (is it running on " + url + "?)");
    }
    if (auto handled = (*bus)->HandleOnce(std::chrono::milliseconds(100)); !handled)
      return Fail(handled.error().message);
  }
  if (refused) return 1;
  if (!follow_session || action != selfcal::calibration_request_t::START) return 0;
  const std::int64_t session_start = timing::RealtimeUs();
  while (!ended || (!result && timing::RealtimeUs() - session_start <
                                   static_cast<std::int64_t>(session_timeout * 1e6))) {
    if (ended &&
        timing::RealtimeUs() - session_start > static_cast<std::int64_t>(session_timeout * 1e6))
      break;
    if (!ended &&
        timing::RealtimeUs() - session_start > static_cast<std::int64_t>(session_timeout * 1e6)) {
      return Fail("session " + session_id + " did not end within " +
                  std::to_string(session_timeout) + " s");
    }
    if (ended && !result) {
      // The result follows the terminal status immediately; do not wait long for it.
      (void)(*bus)->HandleOnce(std::chrono::milliseconds(500));
      break;
    }
    if (auto handled = (*bus)->HandleOnce(std::chrono::milliseconds(100)); !handled)
      return Fail(handled.error().message);
  }
  if (result && result->validation_rms_before >= 0) {
    std::printf("session %s: validation RMS %.3f mm -> %.3f mm, %d iterations, %.1f s%s%s\n",
                result->session_id.c_str(), result->validation_rms_before * 1e3,
                result->validation_rms_after * 1e3, result->iterations, result->runtime,
                result->model_path.empty() ? "" : "; model ", result->model_path.c_str());
  }
  return final_state == selfcal::calibration_status_t::ACCEPTED ? 0 : 1;
}

void AddPlainRequestCommand(CLI::App& app, const std::string& name, const std::string& description,
                            std::int8_t action) {
  auto* command = app.add_subcommand(name, description);
  auto client = std::make_shared<DaemonClientOptions>();
  auto by = std::make_shared<std::string>(DefaultRequester());
  AddDaemonClientOptions(command, *client);
  command->add_option("--by", *by, "Who asks, for the logs and the history");
  command->callback(
      [client, by, action] { exit_code = SendRequest(*client, action, "", *by, false, 0); });
}

}  // namespace selfcal::cli
