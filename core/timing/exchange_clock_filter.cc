#include "core/timing/exchange_clock_filter.h"

namespace selfcal::timing {

ExchangeClockFilter::ExchangeClockFilter(ExchangeClockOptions options)
    : options_(options),
      window_({.slope_min = 1.0 - options.max_rate_error,
               .slope_max = 1.0 + options.max_rate_error,
               .max_samples = options.max_samples,
               .refit_all_below = options.refit_all_below,
               .refit_every = 10}) {}

void ExchangeClockFilter::Reset() { window_.Reset(); }

void ExchangeClockFilter::AddExchange(double host_send_us, double host_receive_us,
                                      std::int64_t device_ticks) {
  const double device_us = static_cast<double>(device_ticks) * options_.tick_us;
  // The counter became d within (t_send - 1 tick * rate, t_receive]; the rate's deviation from 1
  // moves that bound by under a thousandth of a tick.
  window_.Add({device_us, host_send_us - options_.tick_us, host_receive_us},
              host_receive_us - options_.window_us);
}

}  // namespace selfcal::timing
