#include "daemon/clock.h"

#include <sstream>

namespace selfcal::daemon {

std::int64_t Us(double seconds) { return static_cast<std::int64_t>(seconds * 1e6); }

std::string Millis(std::int64_t us) {
  std::ostringstream out;
  out.precision(3);
  out << static_cast<double>(us) / 1000.0 << " ms";
  return out.str();
}

}  // namespace selfcal::daemon
