// What the subcommands share: the start-up kit's error reporting (prints "error: <reason>" on
// stderr and returns the exit code, 1 unless told otherwise).
#pragma once

#include "protocols/program/program.h"

namespace selfcal::cli {

using program::Fail;

}  // namespace selfcal::cli
