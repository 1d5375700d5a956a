#include "drivers/hokuyo/scan_timer.h"

#include <cmath>

namespace selfcal::hokuyo {

ScanTimer::ScanTimer(double nominal_period_us, ScanTimerOptions options)
    : nominal_period_us_(nominal_period_us), options_(options) {
  scratch_.reserve(options_.window_scans + 1);
}

void ScanTimer::Reset() {
  samples_.clear();
  fit_ = timing::IntervalLineFit{};
  last_index_ = 0;
  added_ = 0;
}

timing::ClockJump ScanTimer::Check(std::int64_t timestamp_ms) const {
  if (samples_.empty()) return timing::ClockJump::kNone;
  if (timestamp_ms < last_timestamp_ms_) return timing::ClockJump::kBackwards;
  if (timestamp_ms - last_timestamp_ms_ > options_.max_gap_ms) return timing::ClockJump::kForward;
  return timing::ClockJump::kNone;
}

double ScanTimer::Add(std::int64_t timestamp_ms) {
  std::int64_t index = 0;
  if (!samples_.empty()) {
    // Scan number from the elapsed time: skipped or lost scans keep their place on the grid.
    const double period = fit_.slope > 0 ? fit_.slope : nominal_period_us_;
    const double elapsed_us = static_cast<double>(timestamp_ms - last_timestamp_ms_) * 1000.0;
    index = last_index_ + std::max<std::int64_t>(1, std::llround(elapsed_us / period));
  }
  last_timestamp_ms_ = timestamp_ms;
  last_index_ = index;
  const double lo = static_cast<double>(timestamp_ms) * 1000.0;
  samples_.push_back({static_cast<double>(index), lo, lo + 1000.0});
  while (samples_.size() > options_.window_scans) samples_.pop_front();
  ++added_;
  if (samples_.size() < options_.refit_all_below || added_ % 8 == 0) {
    scratch_.assign(samples_.begin(), samples_.end());
    fit_ = timing::FitIntervalLine(scratch_, static_cast<double>(index),
                                   nominal_period_us_ * (1.0 - options_.max_period_error),
                                   nominal_period_us_ * (1.0 + options_.max_period_error));
  }
  return fit_.At(static_cast<double>(index));
}

}  // namespace selfcal::hokuyo
