#include "tools/selfcal/cli_util.h"

#include <iostream>

namespace selfcal::cli {

int Fail(const std::string& reason) {
  std::cerr << "error: " << reason << "\n";
  return 1;
}

}  // namespace selfcal::cli
