#include "drivers/hokuyo/scan_timer.h"

#include <cmath>

namespace selfcal::hokuyo {

ScanTimer::ScanTimer(double nominal_period_us, ScanTimerOptions options)
    : nominal_period_us_(nominal_period_us),
      options_(options),
      window_({.slope_min = nominal_period_us * (1.0 - options.max_period_error),
               .slope_max = nominal_period_us * (1.0 + options.max_period_error),
               .max_samples = options.window_scans,
               .refit_all_below = options.refit_all_below,
               .refit_every = 8}) {}

void ScanTimer::Reset() {
  window_.Reset();
  last_index_ = 0;
}

timing::ClockJump ScanTimer::Check(std::int64_t timestamp_ms) const {
  if (window_.empty()) return timing::ClockJump::kNone;
  if (timestamp_ms < last_timestamp_ms_) return timing::ClockJump::kBackwards;
  if (timestamp_ms - last_timestamp_ms_ > options_.max_gap_ms) return timing::ClockJump::kForward;
  return timing::ClockJump::kNone;
}

double ScanTimer::Add(std::int64_t timestamp_ms) {
  std::int64_t index = 0;
  if (!window_.empty()) {
    // Scan number from the elapsed time: skipped or lost scans keep their place on the grid.
    const double period = window_.fit().slope > 0 ? window_.fit().slope : nominal_period_us_;
    const double elapsed_us = static_cast<double>(timestamp_ms - last_timestamp_ms_) * 1000.0;
    index = last_index_ + std::max<std::int64_t>(1, std::llround(elapsed_us / period));
  }
  last_timestamp_ms_ = timestamp_ms;
  last_index_ = index;
  const double lo = static_cast<double>(timestamp_ms) * 1000.0;
  window_.Add({static_cast<double>(index), lo, lo + 1000.0});
  return window_.fit().At(static_cast<double>(index));
}

}  // namespace selfcal::hokuyo
