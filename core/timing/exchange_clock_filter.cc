#include "core/timing/exchange_clock_filter.h"

namespace selfcal::timing {

ExchangeClockFilter::ExchangeClockFilter(ExchangeClockOptions options) : options_(options) {
  scratch_.reserve(options_.max_samples);
}

void ExchangeClockFilter::Reset() {
  samples_.clear();
  fit_ = IntervalLineFit{};
  added_ = 0;
}

void ExchangeClockFilter::AddExchange(double host_send_us, double host_receive_us,
                                      std::int64_t device_ticks) {
  const double device_us = static_cast<double>(device_ticks) * options_.tick_us;
  // The counter became d within (t_send - 1 tick * rate, t_receive]; the rate's deviation from 1
  // moves that bound by under a thousandth of a tick.
  samples_.push_back({device_us, host_send_us - options_.tick_us, host_receive_us});
  while (!samples_.empty() && (samples_.size() > options_.max_samples ||
                               samples_.front().hi < host_receive_us - options_.window_us)) {
    samples_.pop_front();
  }
  ++added_;
  if (samples_.size() < options_.refit_all_below || added_ % 10 == 0) Refit();
}

void ExchangeClockFilter::Refit() {
  scratch_.assign(samples_.begin(), samples_.end());
  // Reference at the newest sample: the mapping is used near now, where the intercept is best.
  const double x_ref = scratch_.back().x;
  fit_ = FitIntervalLine(scratch_, x_ref, 1.0 - options_.max_rate_error,
                         1.0 + options_.max_rate_error);
}

}  // namespace selfcal::timing
