#include "tools/selfcal/daemon_client.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>
#include <utility>

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

void AddDaemonConfigOption(CLI::App* command, std::string& config, const std::string& what_for) {
  AddOptionalInputFile(command, "-c,--config", config,
                       "The daemon's configuration (" + what_for + ")")
      ->capture_default_str();
}

void AddDaemonClientOptions(CLI::App* command, DaemonClientOptions& options) {
  AddDaemonConfigOption(command, options.config, "key file, LCM URL, channels");
  AddOptionalInputFile(command, "--key", options.key_file,
                       "Key file to sign with (default: the configuration's)");
  command->add_option("--lcm-url", options.lcm_url, "LCM URL (default: the configuration's)");
  command->add_option("--timeout", options.timeout, "Seconds to wait for the daemon's answer");
}

std::string DefaultRequester() {
  const char* user = getenv("USER");
  char host[256] = {};
  gethostname(host, sizeof(host) - 1);
  return std::string(user ? user : "unknown") + "@" + host;
}

namespace {

using Status_t = selfcal::calibration_status_t;

std::int64_t Microseconds(double seconds) { return static_cast<std::int64_t>(seconds * 1e6); }

// What a client learns from the daemon's statuses about its request and, after a START, about
// the session it started: the answer, each new line of progress, and how the session ended —
// from its terminal status or, if that was missed, from the last session a later status names.
class RequestFollower {
 public:
  explicit RequestFollower(std::string nonce) : nonce_(std::move(nonce)) {}

  void OnStatus(const Status_t& status, std::int64_t now) {
    last_status_time_ = now;
    if (!answered_) return OnAnswer(status);
    if (!status.refusal.empty()) return;  // someone else's request
    if (status.session_id == session_id_) return OnProgress(status);
    if (status.last_session_id == session_id_) {
      EndWith(status.last_session_state);
    } else if (!ended_) {
      lost_ =
          "selfcald no longer knows session " + session_id_ +
          " (it restarted, or a later session ended): its outcome is unknown; 'selfcal history' "
          "on the robot PC lists it";
    }
  }

  bool answered() const { return answered_; }
  bool refused() const { return refused_; }
  bool ended() const { return ended_ || !lost_.empty(); }
  const std::string& lost() const { return lost_; }
  const std::string& session_id() const { return session_id_; }
  std::int8_t final_state() const { return final_state_; }
  std::int64_t last_status_time() const { return last_status_time_; }

 private:
  void OnAnswer(const Status_t& status) {
    if (status.request_nonce != nonce_) return;
    answered_ = true;
    refused_ = !status.refusal.empty();
    std::cout << (refused_ ? status.refusal : "selfcald: " + status.message) << "\n";
    if (refused_) return;
    session_id_ = status.session_id;
    if (!session_id_.empty()) return OnProgress(status);
    // Idle already: a session that ended while starting (its check failed) is the last one.
    session_id_ = status.last_session_id;
    EndWith(status.last_session_state);
  }
  void OnProgress(const Status_t& status) {
    char line[512];
    std::snprintf(line, sizeof(line), "%-11s %3.0f %%  %s", daemon::WireStateName(status.state),
                  std::floor(100.0 * status.progress / 5.0) * 5.0, status.message.c_str());
    if (line != last_line_) {
      std::cout << line << "\n" << std::flush;
      last_line_ = line;
    }
    EndWith(status.state);
  }
  void EndWith(std::int8_t wire_state) {
    const auto state = daemon::StateFromWire(wire_state);
    if (!state || !daemon::IsTerminal(*state) || ended_) return;
    ended_ = true;
    final_state_ = wire_state;
  }

  std::string nonce_;
  bool answered_ = false, refused_ = false, ended_ = false;
  std::string session_id_, last_line_, lost_;
  std::int8_t final_state_ = -1;
  std::int64_t last_status_time_ = 0;
};

void PrintResult(const selfcal::calibration_result_t& result) {
  if (result.validation_rms_before < 0) return;
  std::printf("session %s: validation RMS %.3f mm -> %.3f mm, %d iterations, %.1f s%s%s\n",
              result.session_id.c_str(), result.validation_rms_before * 1e3,
              result.validation_rms_after * 1e3, result.iterations, result.runtime,
              result.model_path.empty() ? "" : "; model ", result.model_path.c_str());
  if (!result.change.empty()) std::printf("what changed: %s\n", result.change.c_str());
}

}  // namespace

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

  RequestFollower follower(request.nonce);
  std::optional<selfcal::calibration_result_t> result;
  (*bus)->Subscribe(config->channels.calibration_status, [&](const BusMessage& message) {
    auto status = DecodeLcm<Status_t>(message.data, message.channel);
    if (status) follower.OnStatus(*status, timing::MonotonicNs() / 1000);
  });
  (*bus)->Subscribe(config->channels.calibration_result, [&](const BusMessage& message) {
    auto decoded = DecodeLcm<selfcal::calibration_result_t>(message.data, message.channel);
    if (decoded && decoded->session_id == follower.session_id()) result = *decoded;
  });
  auto published = (*bus)->Publish(config->channels.calibration_request, request);
  if (!published) return Fail(published.error().message);

  const auto handle = [&](int ms) { return (*bus)->HandleOnce(std::chrono::milliseconds(ms)); };
  const std::int64_t start = timing::MonotonicNs() / 1000;
  while (!follower.answered()) {
    if (timing::MonotonicNs() / 1000 - start > Microseconds(options.timeout)) {
      return Fail("no answer from selfcald on " + config->channels.calibration_status + " within " +
                  std::to_string(options.timeout) + " s (is it running on " + url + "?)");
    }
    if (auto handled = handle(100); !handled) return Fail(handled.error().message);
  }
  if (follower.refused()) return 1;
  if (!follow_session || action != selfcal::calibration_request_t::START) return 0;
  if (follower.session_id().empty())
    return Fail("selfcald accepted the START but names no session");
  // The daemon publishes at status_rate_hz whatever it does: a silence of several periods means
  // it stopped or the network between us did.
  const double silence_s = std::max(3.0, 5.0 / config->status_rate_hz);
  while (!follower.ended()) {
    const std::int64_t now = timing::MonotonicNs() / 1000;
    if (now - start > Microseconds(session_timeout)) {
      return Fail("session " + follower.session_id() + " did not end within " +
                  std::to_string(session_timeout) + " s");
    }
    if (now - follower.last_status_time() > Microseconds(silence_s)) {
      return Fail("no status from selfcald for " + std::to_string(silence_s) +
                  " s while following session " + follower.session_id() +
                  " (it stopped, or the network to it did)");
    }
    if (auto handled = handle(100); !handled) return Fail(handled.error().message);
  }
  if (!follower.lost().empty()) return Fail(follower.lost());
  // The result follows the terminal status immediately; do not wait long for it.
  if (!result) (void)handle(500);
  if (result) PrintResult(*result);
  return follower.final_state() == Status_t::ACCEPTED ? 0 : 1;
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
