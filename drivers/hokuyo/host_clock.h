// Host clocks. Filters run on CLOCK_MONOTONIC (immune to NTP steps); published utime is
// CLOCK_REALTIME, converted at publication.
#pragma once

#include <cstdint>
#include <ctime>

namespace selfcal::hokuyo {

inline double MonotonicUs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) * 1e6 + static_cast<double>(ts.tv_nsec) * 1e-3;
}

// CLOCK_REALTIME - CLOCK_MONOTONIC [us], sampled now.
inline double RealtimeMinusMonotonicUs() {
  timespec mono{};
  timespec real{};
  clock_gettime(CLOCK_MONOTONIC, &mono);
  clock_gettime(CLOCK_REALTIME, &real);
  return (static_cast<double>(real.tv_sec) - static_cast<double>(mono.tv_sec)) * 1e6 +
         (static_cast<double>(real.tv_nsec) - static_cast<double>(mono.tv_nsec)) * 1e-3;
}

}  // namespace selfcal::hokuyo
