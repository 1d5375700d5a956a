// Sub-millisecond scan start times from millisecond scan timestamps (docs/hokuyo.md).
//
// The mirror turns at a steady rate of the device's own crystal, so scan n starts at device time
// D_n = c + P * n. Its timestamp ts_n = floor(D_n / 1 ms) says D_n lies in [ts_n, ts_n + 1) ms.
// The motor is not phase-locked to the millisecond counter, so the fraction of D_n slides from
// scan to scan and a window of intervals fixes c and P to microseconds (FitIntervalLine).
// Assumption (named in docs/hokuyo.md): the timestamp is taken when the mirror passes step 0.
#pragma once

#include <cstdint>

#include "core/timing/clock_jump.h"
#include "core/timing/interval_line_fit.h"

namespace selfcal::hokuyo {

struct ScanTimerOptions {
  std::size_t window_scans = 400;  // 10 s at 40 Hz
  double max_period_error = 2e-3;  // |P / P_nominal - 1| bound (motor speed tolerance)
  // Once this many scans are held, refit on every 8th scan only and extrapolate the line in
  // between (the fit costs O(window); the line moves by microseconds per second).
  std::size_t refit_all_below = 100;
  // Scans further apart than this in device time mean the counter jumped (a reboot without
  // link loss), not a pause: the stream never pauses that long without a stall timeout.
  std::int64_t max_gap_ms = 60000;
};

class ScanTimer {
 public:
  ScanTimer(double nominal_period_us, ScanTimerOptions options = {});

  // Adds scan timestamp [ms, unwrapped] and returns the estimated device time [us] of its start.
  double Add(std::int64_t timestamp_ms);
  // Whether `timestamp_ms` continues the scans added so far (kNone) or the counter jumped back
  // (kBackwards) or ahead (kForward). Always kNone before the first scan.
  timing::ClockJump Check(std::int64_t timestamp_ms) const;
  void Reset();

  double period_us() const { return window_.fit().slope; }
  bool consistent() const { return window_.fit().consistent; }
  double margin_us() const { return window_.fit().margin; }
  std::size_t scans() const { return window_.size(); }
  // Rotation number of the last scan added (0 for the first since Reset).
  std::int64_t last_index() const { return last_index_; }

 private:
  double nominal_period_us_;
  ScanTimerOptions options_;
  timing::IntervalLineWindow window_;  // x = scan number, [lo, hi] = device us
  std::int64_t last_timestamp_ms_ = 0;
  std::int64_t last_index_ = 0;
};

}  // namespace selfcal::hokuyo
