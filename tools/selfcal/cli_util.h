// Helpers shared by the subcommands: uniform error reporting.
#pragma once

#include <string>

namespace selfcal::cli {

// Prints "error: <reason>" on stderr and returns the exit code for bad input (1).
int Fail(const std::string& reason);

}  // namespace selfcal::cli
