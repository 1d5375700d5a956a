#include "daemon/clock.h"

#include <spdlog/fmt/fmt.h>

namespace selfcal::daemon {

std::int64_t Us(double seconds) { return static_cast<std::int64_t>(seconds * 1e6); }

// Fixed point: an age of a second must not print as "1e+03 ms".
std::string Millis(std::int64_t us) {
  return fmt::format("{:.1f} ms", static_cast<double>(us) / 1000.0);
}

}  // namespace selfcal::daemon
