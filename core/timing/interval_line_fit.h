// A line through samples known only as intervals: lo_i <= a + b * (x_i - x_ref) <= hi_i.
// Clocks read as whole ticks give such samples: a request/reply exchange says the device counter
// read d at some host instant between sending and receiving (ExchangeClockFilter); a Hokuyo scan
// timestamp says the scan began while the counter read ts. Each is an interval that certainly
// holds the truth, whatever the latency. Many intervals at varying phases pin a line down far
// below one tick (a vernier).
//
// Estimator (set membership): the lines that pass every interval, with a slope in [slope_min,
// slope_max], form a convex set. The intercept at x_ref is the middle of that set's extent along
// the intercept (the smallest guaranteed error at x_ref); the slope is the middle of the feasible
// slopes, so few samples keep it at the prior's centre. When no line passes every interval (a model
// change, a reboot, a bad sample), the minimax line (largest smallest margin) is used.
#pragma once

#include <cstddef>
#include <deque>
#include <limits>
#include <span>
#include <vector>

namespace selfcal::timing {

struct IntervalSample {
  double x = 0;
  double lo = 0;
  double hi = 0;
};

struct IntervalLineFit {
  double x_ref = 0;
  double intercept = 0;  // a: value at x_ref
  double slope = 0;      // b
  // Half the width of the feasible intercept range at the chosen slope: > 0 when a line passes
  // every interval (then the intercept is known to +- margin), < 0 when none does.
  double margin = 0;
  bool consistent = false;
  double At(double x) const { return intercept + slope * (x - x_ref); }
};

// `samples` must not be empty.
IntervalLineFit FitIntervalLine(std::span<const IntervalSample> samples, double x_ref,
                                double slope_min, double slope_max);

struct IntervalWindowOptions {
  double slope_min = 0;
  double slope_max = 0;
  std::size_t max_samples = 1000;
  // Once this many samples are held, refit on every `refit_every`-th new one only: the fit
  // costs O(samples), and the line moves little between refits.
  std::size_t refit_all_below = 200;
  std::size_t refit_every = 10;
};

// FitIntervalLine over a sliding window of samples, referenced at the newest: the mapping is
// used near now, where the intercept is best. Between refits the last line is extrapolated.
class IntervalLineWindow {
 public:
  explicit IntervalLineWindow(IntervalWindowOptions options);

  // Adds a sample, then forgets the oldest beyond max_samples and those whose hi is below
  // `forget_hi_below` (a time window); the newest sample is always kept.
  void Add(const IntervalSample& sample,
           double forget_hi_below = -std::numeric_limits<double>::infinity());
  void Reset();

  // The last fit; a default (zero) line before the first sample.
  const IntervalLineFit& fit() const { return fit_; }
  std::size_t size() const { return samples_.size(); }
  bool empty() const { return samples_.empty(); }

 private:
  IntervalWindowOptions options_;
  std::deque<IntervalSample> samples_;
  std::vector<IntervalSample> scratch_;
  IntervalLineFit fit_;
  std::size_t added_ = 0;
};

}  // namespace selfcal::timing
