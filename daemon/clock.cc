#include "daemon/clock.h"

#include <ctime>

namespace selfcal::daemon {

std::int64_t NowUtime() {
  timespec now{};
  clock_gettime(CLOCK_REALTIME, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1000000 + now.tv_nsec / 1000;
}

}  // namespace selfcal::daemon
