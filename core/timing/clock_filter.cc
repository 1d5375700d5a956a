#include "core/timing/clock_filter.h"

#include <algorithm>
#include <cmath>

namespace selfcal::timing {

ClockFilter::ClockFilter(const ClockFilterOptions& options)
    : options_(options),
      ring_(std::max<std::size_t>(options.capacity, 2)),
      bin_filled_(static_cast<std::size_t>(std::max(options.bins, 1))) {
  hull_.reserve(ring_.size());
}

void ClockFilter::Reset() {
  head_ = count_ = 0;
  settled_ = fitted_ = false;
  late_since_us_.reset();
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

ClockJump ClockFilter::Classify(std::int64_t device_us, std::int64_t host_receive_us) {
  if (count_ == 0) return ClockJump::kNone;
  if (device_us <= At(count_ - 1).device_us) return ClockJump::kBackwards;
  if (!fitted_) return ClockJump::kNone;
  const double error = static_cast<double>(host_receive_us - ToHost(device_us));
  const double limit = options_.reset_jump_s * 1e6;
  if (error < -limit) return ClockJump::kOffTheLine;  // received before the line says it was sent
  if (error <= limit) {
    late_since_us_.reset();
    return ClockJump::kNone;
  }
  // Far later than the line: a reader that stalled drains its backlog within moments and its
  // samples only rise above the envelope, while a stepped clock stays late. Restarting on the
  // first late sample would blind the mapping for settle_s after every stall. Before settling
  // there is nothing to keep: the window holds a backlog from the start, drop it.
  if (!settled_) return ClockJump::kOffTheLine;
  if (!late_since_us_) late_since_us_ = host_receive_us;
  const double late_for_us = static_cast<double>(host_receive_us - *late_since_us_);
  return late_for_us > options_.settle_s * 1e6 ? ClockJump::kOffTheLine : ClockJump::kNone;
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
  // A hull steeper than the drift bound is a backlog read in a burst, not a clock: the receive
  // times say nothing yet about when the samples were sent.
  bool plausible = true;
  if (count_ >= 2 && span > 0 && span >= options_.min_drift_span_s * 1e6) {
    plausible = FitLowerHull();
  } else {
    slope_ = 0;
    intercept_ = R(At(0));
  }
  // A hull edge lies under every sample; a clamped or flat line may not: lower it onto the
  // envelope so that it never predicts a negative delay.
  if (!plausible || slope_ == 0) {
    double lowest = 0;
    for (std::size_t i = 0; i < count_; ++i) {
      const Pair& p = At(i);
      lowest = std::min(lowest, R(p) - (intercept_ + slope_ * T(p)));
    }
    intercept_ += lowest;
  }
  fitted_ = true;
  settled_ = plausible && count_ >= options_.settle_samples && span >= options_.settle_s * 1e6 &&
             EveryBinHoldsASample(t0, span);
}

bool ClockFilter::FitLowerHull() {
  // The lower convex hull of (t, r), left to right (Andrew's monotone chain; t increases).
  hull_.clear();
  double sum_t = 0;
  for (std::size_t i = 0, j = head_; i < count_; ++i, j = j + 1 == ring_.size() ? 0 : j + 1) {
    const HullPoint p{T(ring_[j]), R(ring_[j])};
    sum_t += p.t;
    while (hull_.size() >= 2) {
      const HullPoint& a = hull_[hull_.size() - 2];
      const HullPoint& b = hull_.back();
      // Keep b only if a -> b -> p turns counterclockwise.
      if ((b.t - a.t) * (p.r - a.r) - (b.r - a.r) * (p.t - a.t) > 0) break;
      hull_.pop_back();
    }
    hull_.push_back(p);
  }
  // Of the lines under every sample, the one highest at the mean time: the hull's edge over it.
  const double mean_t = sum_t / static_cast<double>(count_);
  std::size_t edge = 0;
  while (edge + 2 < hull_.size() && hull_[edge + 1].t < mean_t) ++edge;
  const HullPoint& a = hull_[edge];
  const HullPoint& b = hull_[edge + 1];
  const double slope = (b.r - a.r) / (b.t - a.t);
  slope_ = std::clamp(slope, -options_.max_drift, options_.max_drift);
  intercept_ = a.r - slope_ * a.t;
  return slope == slope_;
}

bool ClockFilter::EveryBinHoldsASample(double t0, double span) {
  if (span <= 0) return bin_filled_.size() == 1;
  std::fill(bin_filled_.begin(), bin_filled_.end(), 0);
  const double bins = static_cast<double>(bin_filled_.size());
  for (std::size_t i = 0, j = head_; i < count_; ++i, j = j + 1 == ring_.size() ? 0 : j + 1) {
    const auto b = static_cast<std::size_t>((T(ring_[j]) - t0) / span * bins);
    bin_filled_[std::min(b, bin_filled_.size() - 1)] = 1;
  }
  return std::all_of(bin_filled_.begin(), bin_filled_.end(),
                     [](char filled) { return filled != 0; });
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
