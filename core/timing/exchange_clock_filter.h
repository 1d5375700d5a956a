// Device-to-host clock mapping from request/reply exchanges (the Hokuyo's TM1, docs/hokuyo.md,
// "Clock mapping"), for a device whose clock is read as whole ticks.
//
// The device reports a tick counter d. A request written at host time t_send and answered at
// t_receive was read at some instant in between, while the counter showed d; so the host time at
// which the counter became d lies in [t_send - 1 tick, t_receive], whatever the latency and its
// jitter. The filter fits host = a + b * device to these intervals over a sliding window
// (FitIntervalLine): the window follows a drifting rate (b - 1 is the drift, tens of ppm),
// exchanges at random phases of the counter resolve it far below one tick.
// Error: within margin_us() of the truth while consistent(); the round trip bounds it from below.
// For clocks known only from receive times (no request), use ClockFilter.
#pragma once

#include <cstdint>

#include "core/timing/interval_line_fit.h"

namespace selfcal::timing {

struct ExchangeClockOptions {
  double tick_us = 1000;           // one count of the device counter
  double window_us = 20e6;         // exchanges older than this (host time) are forgotten
  double max_rate_error = 300e-6;  // |b - 1| bound: crystals are within 100 ppm; 3x margin
  std::size_t max_samples = 1000;
  // Once this many samples are held, refit on every 10th new one only (the fit costs
  // O(samples); at 50 exchanges per second the line is then at most 0.2 s old).
  std::size_t refit_all_below = 200;
};

class ExchangeClockFilter {
 public:
  explicit ExchangeClockFilter(ExchangeClockOptions options = {});

  // One exchange: host times [us, monotonic] and the unwrapped device counter [ticks].
  void AddExchange(double host_send_us, double host_receive_us, std::int64_t device_ticks);
  void Reset();

  bool ready() const { return !window_.empty(); }
  std::size_t samples() const { return window_.size(); }
  // Host time [us] at device time [us] (continuous; the counter reads floor(device_us / tick)).
  double HostFromDevice(double device_us) const { return window_.fit().At(device_us); }
  // Host seconds per device second (1 + drift).
  double rate() const { return window_.fit().slope; }
  // Half-width of the feasible offsets [us]: the guaranteed bound when consistent.
  double margin_us() const { return window_.fit().margin; }
  bool consistent() const { return window_.fit().consistent; }

 private:
  ExchangeClockOptions options_;
  IntervalLineWindow window_;  // x = device us, [lo, hi] = host us
};

}  // namespace selfcal::timing
