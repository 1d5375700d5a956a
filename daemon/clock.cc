#include "daemon/clock.h"

#include <ctime>
#include <sstream>

namespace selfcal::daemon {

std::int64_t NowUtime() {
  timespec now{};
  clock_gettime(CLOCK_REALTIME, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1000000 + now.tv_nsec / 1000;
}

std::int64_t MonotonicUs() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1000000 + now.tv_nsec / 1000;
}

std::int64_t Us(double seconds) { return static_cast<std::int64_t>(seconds * 1e6); }

std::string Millis(std::int64_t us) {
  std::ostringstream out;
  out.precision(3);
  out << static_cast<double>(us) / 1000.0 << " ms";
  return out.str();
}

}  // namespace selfcal::daemon
