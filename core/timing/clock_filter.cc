#include "core/timing/clock_filter.h"

#include <algorithm>
#include <cmath>

namespace selfcal::timing {

ClockFilter::ClockFilter(const ClockFilterOptions& options)
    : options_(options),
      ring_(std::max<std::size_t>(options.capacity, 2)),
      bin_t_(static_cast<std::size_t>(std::max(options.bins, 1))),
      bin_r_(static_cast<std::size_t>(std::max(options.bins, 1))) {}

void ClockFilter::Reset() {
  head_ = count_ = 0;
  settled_ = fitted_ = false;
  intercept_ = slope_ = bound_ = 0;
}

ClockJump ClockFilter::Add(std::int64_t device_us, std::int64_t host_receive_us) {
  const ClockJump jump = Classify(device_us, host_receive_us);
  if (jump != ClockJump::kNone) {
    Reset();
    ++restarts_;
  }
  Push(device_us, host_receive_us);
  if (options_.never_early) {
    // The bound is all the mapping needs: skip the O(window) fit (the Wenglor runs at kHz).
    fitted_ = true;
    settled_ = count_ >= options_.settle_samples &&
               T(At(count_ - 1)) - T(At(0)) >= options_.settle_s * 1e6;
  } else {
    Refit();
  }
  return jump;
}

std::int64_t ClockFilter::Map(std::int64_t device_us, std::int64_t host_receive_us) {
  (void)Add(device_us, host_receive_us);
  return std::min(ToHost(device_us), host_receive_us);
}

ClockJump ClockFilter::Classify(std::int64_t device_us, std::int64_t host_receive_us) const {
  if (count_ == 0) return ClockJump::kNone;
  if (device_us <= At(count_ - 1).device_us) return ClockJump::kBackwards;
  if (fitted_) {
    const double error = static_cast<double>(host_receive_us - ToHost(device_us));
    if (std::abs(error) > options_.reset_jump_s * 1e6) return ClockJump::kOffTheLine;
  }
  return ClockJump::kNone;
}

void ClockFilter::Push(std::int64_t device_us, std::int64_t host_receive_us) {
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
  const double window_us = options_.window_s * 1e6;
  while (count_ > 1 && static_cast<double>(device_us - At(0).device_us) > window_us) {
    head_ = (head_ + 1) % ring_.size();
    --count_;
  }
  // The least upper bound of r: each sample bounds it from above, loosened by the drift bound
  // per unit of device time since.
  const Pair& newest = At(count_ - 1);
  const double t = T(newest);
  bound_ =
      count_ == 1 ? R(newest) : std::min(R(newest), bound_ + options_.max_drift * (t - newest_t_));
  newest_t_ = t;
}

void ClockFilter::Refit() {
  const double t0 = T(At(0));
  const double span = T(At(count_ - 1)) - t0;
  FitBinMinima(t0, span);
  // A line through bin minima can still sit above an individual lower point: lower the line
  // onto the envelope so that it never predicts a negative delay.
  double lowest = 0;
  for (std::size_t i = 0; i < count_; ++i) {
    const Pair& p = At(i);
    lowest = std::min(lowest, R(p) - (intercept_ + slope_ * T(p)));
  }
  intercept_ += lowest;
  fitted_ = true;
  const auto filled = static_cast<int>(
      std::count_if(bin_r_.begin(), bin_r_.end(), [](double r) { return std::isfinite(r); }));
  settled_ = count_ >= options_.settle_samples && span >= options_.settle_s * 1e6 &&
             filled == static_cast<int>(bin_r_.size());
}

void ClockFilter::FitBinMinima(double t0, double span) {
  const std::size_t bins = bin_t_.size();
  std::fill(bin_r_.begin(), bin_r_.end(), std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < count_; ++i) {
    const double t = T(At(i));
    const double r = R(At(i));
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
  if (n >= 2 && span > 0 && span >= options_.min_drift_span_s * 1e6 && denominator > 0) {
    slope_ = std::clamp((n * str - st * sr) / denominator, -options_.max_drift, options_.max_drift);
    intercept_ = (sr - slope_ * st) / n;
  } else {
    slope_ = 0;
    intercept_ = sr / std::max(n, 1.0);
  }
}

double ClockFilter::OffsetAt(double t) const {
  if (options_.never_early) {
    const double age = std::abs(t - newest_t_);
    return age > 0 ? bound_ + options_.max_drift * age : bound_;
  }
  return intercept_ + slope_ * t;
}

double ClockFilter::offset_us() const {
  return static_cast<double>(reference_offset_us_) + OffsetAt(newest_t_);
}

std::int64_t ClockFilter::ToHost(std::int64_t device_us) const {
  const double t = static_cast<double>(device_us - reference_device_us_);
  return device_us + reference_offset_us_ + static_cast<std::int64_t>(std::llround(OffsetAt(t)));
}

}  // namespace selfcal::timing
