// Subcommands of `selfcal`. Each Register* adds one subcommand to the app; the callback it sets
// returns the process exit code through `exit_code`.
#pragma once

#include <CLI/CLI.hpp>
#include <optional>

namespace selfcal::cli {

// Set by a subcommand's callback; main() returns it.
extern int exit_code;

void RegisterAll(CLI::App& app);

// After RegisterAll on an app that captures every default: --help shows each option's default
// ("--timeout FLOAT=5"), except where the value only marks "not given" (-1, an empty list) or the
// help text states the default in words ("default: the scenario's"), where the raw value would
// mislead.
void ShowDefaultsInHelp(CLI::App& app);

// Before parsing: the first word of the command line that is no option must name a command.
// CLI11 answers a typo with "A subcommand is required", and `typo --help` with the general help
// and exit 0. Returns the exit code (usage) after naming the word and the nearest command.
std::optional<int> RefuseUnknownCommand(CLI::App& app, int argc, char** argv);

// Before parsing: no command at all is answered with the list of commands (a usage error), and
// `help [COMMAND]` with the general help or the command's, as `[COMMAND] --help` would. Returns
// the exit code when it answered.
std::optional<int> AnswerHelp(CLI::App& app, int argc, char** argv);

}  // namespace selfcal::cli
