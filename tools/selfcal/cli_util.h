// What the subcommands share: the start-up kit's error reporting (prints "error: <reason>" on
// stderr and returns the exit code, 1 unless told otherwise), and the checks of path options.
#pragma once

#include <CLI/CLI.hpp>

#include "protocols/program/program.h"

namespace selfcal::cli {

using program::Fail;

// Checks for path options, when the command line is parsed: a folder where a file is expected
// ("--robot: config is a folder, not a file"), and an output file that is a folder or whose
// folder does not exist, are usage errors (exit 2) before any work. A missing input file is left
// to the reader, whose error says more.
extern const CLI::Validator kFileNotFolder;
extern const CLI::Validator kOutputFile;

// An input file the command cannot do without: a required option checked with kFileNotFolder.
CLI::Option* AddInputFile(CLI::App* command, const std::string& name, std::string& file,
                          const std::string& description);
// An input file the command can do without: an option checked with kFileNotFolder.
CLI::Option* AddOptionalInputFile(CLI::App* command, const std::string& name, std::string& file,
                                  const std::string& description);
// A file the command writes: an option checked with kOutputFile.
CLI::Option* AddOutputFile(CLI::App* command, const std::string& name, std::string& file,
                           const std::string& description);
// The simulation scenario a command starts from: its required first positional argument.
CLI::Option* AddScenarioFile(CLI::App* command, std::string& scenario);

}  // namespace selfcal::cli
