// Subcommands of `selfcal`. Each Register* adds one subcommand to the app; the callback it sets
// returns the process exit code through `exit_code`.
#pragma once

#include <CLI/CLI.hpp>

namespace selfcal::cli {

// Set by a subcommand's callback; main() returns it.
extern int exit_code;

void RegisterAll(CLI::App& app);

}  // namespace selfcal::cli
