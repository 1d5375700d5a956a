// The host's clocks, read one way by every driver, simulator and the daemon: CLOCK_REALTIME for
// the time stamps that are published (LCM's utime), CLOCK_MONOTONIC for filters, deadlines and
// rates, which must not jump when NTP steps the wall clock.
#pragma once

#include <cstdint>

namespace selfcal::timing {

std::int64_t RealtimeNs();
std::int64_t RealtimeUs();  // LCM's utime
std::int64_t MonotonicNs();
double MonotonicUs();
// CLOCK_REALTIME - CLOCK_MONOTONIC [us], sampled now: what turns a monotonic time into utime.
double RealtimeMinusMonotonicUs();

}  // namespace selfcal::timing
