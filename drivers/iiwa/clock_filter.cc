#include "drivers/iiwa/clock_filter.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace selfcal {

ClockFilter::ClockFilter(const Options& options)
    : options_(options),
      ring_(options.capacity),
      bin_t_(static_cast<std::size_t>(options.bins)),
      bin_r_(static_cast<std::size_t>(options.bins)) {}

void ClockFilter::Reset() {
  head_ = count_ = 0;
  settled_ = fitted_ = false;
  intercept_ = slope_ = 0;
}

bool ClockFilter::Add(std::int64_t device_us, std::int64_t host_receive_us) {
  bool restarted = false;
  if (count_ > 0) {
    const Pair& newest = At(count_ - 1);
    bool jump = device_us < newest.device_us;
    if (fitted_) {
      const double predicted = static_cast<double>(ToHost(device_us));
      jump = jump || std::abs(static_cast<double>(host_receive_us) - predicted) >
                         options_.reset_jump_s * 1e6;
    }
    if (jump) {
      Reset();
      restarted = true;
    }
  }
  if (count_ == 0) {
    reference_device_us_ = device_us;
    reference_offset_us_ = host_receive_us - device_us;
  }
  if (count_ == ring_.size()) {
    head_ = (head_ + 1) % ring_.size();
    --count_;
  }
  ring_[(head_ + count_) % ring_.size()] = {device_us, host_receive_us};
  ++count_;
  // Forget samples that left the window.
  const auto window_us = static_cast<std::int64_t>(options_.window_s * 1e6);
  while (count_ > 1 && device_us - At(0).device_us > window_us) {
    head_ = (head_ + 1) % ring_.size();
    --count_;
  }
  Refit();
  return !restarted;
}

void ClockFilter::Refit() {
  const double t0 = static_cast<double>(At(0).device_us - reference_device_us_);
  const double t1 = static_cast<double>(At(count_ - 1).device_us - reference_device_us_);
  const double span = t1 - t0;
  const std::size_t bins = bin_t_.size();
  std::fill(bin_r_.begin(), bin_r_.end(), std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < count_; ++i) {
    const Pair& p = At(i);
    const double t = static_cast<double>(p.device_us - reference_device_us_);
    const double r = static_cast<double>(p.host_us - p.device_us - reference_offset_us_);
    std::size_t b =
        span > 0 ? static_cast<std::size_t>((t - t0) / span * static_cast<double>(bins)) : 0;
    b = std::min(b, bins - 1);
    if (r < bin_r_[b]) {
      bin_r_[b] = r;
      bin_t_[b] = t;
    }
  }
  // Least squares through the non-empty bins' minima.
  double n = 0, st = 0, sr = 0, stt = 0, str = 0;
  for (std::size_t b = 0; b < bins; ++b) {
    if (!std::isfinite(bin_r_[b])) continue;
    n += 1;
    st += bin_t_[b];
    sr += bin_r_[b];
    stt += bin_t_[b] * bin_t_[b];
    str += bin_t_[b] * bin_r_[b];
  }
  const double denominator = n * stt - st * st;
  if (n >= 2 && span > 0 && denominator > 0) {
    slope_ = (n * str - st * sr) / denominator;
    intercept_ = (sr - slope_ * st) / n;
  } else {
    slope_ = 0;
    intercept_ = sr / std::max(n, 1.0);
  }
  // A line through bin minima can still sit above an individual lower point: lower the line
  // onto the envelope so that it never predicts a negative delay.
  double lowest = 0;
  for (std::size_t b = 0; b < bins; ++b) {
    if (std::isfinite(bin_r_[b])) {
      lowest = std::min(lowest, bin_r_[b] - (intercept_ + slope_ * bin_t_[b]));
    }
  }
  intercept_ += lowest;
  fitted_ = true;
  settled_ = count_ >= options_.settle_samples && span >= options_.settle_s * 1e6 &&
             n == static_cast<double>(bins);
}

std::int64_t ClockFilter::ToHost(std::int64_t device_us) const {
  const double t = static_cast<double>(device_us - reference_device_us_);
  const double r = intercept_ + slope_ * t;
  return device_us + reference_offset_us_ + static_cast<std::int64_t>(std::llround(r));
}

}  // namespace selfcal
