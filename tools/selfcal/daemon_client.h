// What the daemon-client subcommands (trigger, status, abort, history, rollback) share: where
// the daemon is (its configuration file), signing requests with the key file, and following
// the daemon's status.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <memory>
#include <string>

#include "daemon/config.h"

namespace selfcal::cli {

struct DaemonClientOptions {
  std::string config = daemon::InstalledDaemonConfig();
  std::string key_file;  // overrides the configuration's
  std::string lcm_url;   // overrides the configuration's
  double timeout = 5;    // s to wait for the daemon's answer
};

// Adds -c/--config (the daemon's configuration file, installed default shown), read here for
// `what_for`.
void AddDaemonConfigOption(CLI::App* command, std::string& config, const std::string& what_for);

// Adds --config, --key, --lcm-url and --timeout to `command`.
void AddDaemonClientOptions(CLI::App* command, DaemonClientOptions& options);

// Signs and sends a request, waits for the status that answers its nonce, prints it.
// With `follow_session` (START), then follows the session to its end, printing progress.
// Returns the exit code: 0 when accepted (and, when followed, the session ended ACCEPTED).
int SendRequest(const DaemonClientOptions& options, std::int8_t action, const std::string& plan,
                const std::string& requested_by, bool follow_session, double session_timeout);

std::string DefaultRequester();

// Adds the subcommand `name` that sends one signed request of `action` without a plan (abort,
// rollback), with the daemon client options and --by; its result goes to cli::exit_code.
void AddPlainRequestCommand(CLI::App& app, const std::string& name, const std::string& description,
                            std::int8_t action);

}  // namespace selfcal::cli
