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

#include <span>

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

}  // namespace selfcal::timing
