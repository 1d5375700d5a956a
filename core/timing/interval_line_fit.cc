#include "core/timing/interval_line_fit.h"

#include <algorithm>
#include <limits>

namespace selfcal::timing {
namespace {

struct Range {
  double low;
  double high;
};

// Feasible intercepts for slope b: [max(lo_i - b dx_i), min(hi_i - b dx_i)].
Range Intercepts(std::span<const IntervalSample> samples, double x_ref, double b) {
  Range range{-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  for (const IntervalSample& s : samples) {
    const double shift = b * (s.x - x_ref);
    range.low = std::max(range.low, s.lo - shift);
    range.high = std::min(range.high, s.hi - shift);
  }
  return range;
}

// Width of the feasible intercept range: concave and piecewise linear in b.
double Width(std::span<const IntervalSample> samples, double x_ref, double b) {
  const Range r = Intercepts(samples, x_ref, b);
  return r.high - r.low;
}

}  // namespace

IntervalLineFit FitIntervalLine(std::span<const IntervalSample> samples, double x_ref,
                                double slope_min, double slope_max) {
  constexpr int kIterations = 50;  // (2/3)^50 = 2e-9 of the slope range: far below a ppm
  // Largest width (ternary search on a concave function).
  double left = slope_min;
  double right = slope_max;
  for (int i = 0; i < kIterations; ++i) {
    const double m1 = left + (right - left) / 3;
    const double m2 = right - (right - left) / 3;
    if (Width(samples, x_ref, m1) < Width(samples, x_ref, m2)) {
      left = m1;
    } else {
      right = m2;
    }
  }
  const double best = 0.5 * (left + right);
  IntervalLineFit fit;
  fit.x_ref = x_ref;
  if (Width(samples, x_ref, best) < 0) {
    // No line passes every interval: the minimax line.
    const Range r = Intercepts(samples, x_ref, best);
    fit.slope = best;
    fit.intercept = 0.5 * (r.low + r.high);
    fit.margin = 0.5 * (r.high - r.low);
    fit.consistent = false;
    return fit;
  }
  // Feasible slopes form an interval [b1, b2] around `best`: find its ends by bisection.
  auto edge = [&](double inside, double outside) {
    if (Width(samples, x_ref, outside) >= 0) return outside;
    for (int i = 0; i < kIterations; ++i) {
      const double mid = 0.5 * (inside + outside);
      if (Width(samples, x_ref, mid) >= 0) {
        inside = mid;
      } else {
        outside = mid;
      }
    }
    return inside;
  };
  const double b1 = edge(best, slope_min);
  const double b2 = edge(best, slope_max);
  // The feasible set's extent along the intercept at x_ref: the highest feasible intercept is the
  // maximum of the concave upper envelope, the lowest the minimum of the convex lower one, both
  // over [b1, b2]. Their middle is the estimate with the smallest guaranteed error there.
  auto extreme = [&](bool upper) {
    double l = b1;
    double r = b2;
    auto value = [&](double b) {
      const Range range = Intercepts(samples, x_ref, b);
      return upper ? range.high : -range.low;
    };
    for (int i = 0; i < kIterations; ++i) {
      const double m1 = l + (r - l) / 3;
      const double m2 = r - (r - l) / 3;
      if (value(m1) < value(m2)) {
        l = m1;
      } else {
        r = m2;
      }
    }
    return value(0.5 * (l + r)) * (upper ? 1 : -1);
  };
  const double highest = extreme(true);
  const double lowest = extreme(false);
  fit.slope = 0.5 * (b1 + b2);
  fit.intercept = 0.5 * (highest + lowest);
  fit.margin = 0.5 * (highest - lowest);
  fit.consistent = true;
  return fit;
}

IntervalLineWindow::IntervalLineWindow(IntervalWindowOptions options) : options_(options) {
  options_.refit_every = std::max<std::size_t>(options_.refit_every, 1);
  scratch_.reserve(options_.max_samples + 1);
}

void IntervalLineWindow::Reset() {
  samples_.clear();
  fit_ = IntervalLineFit{};
  added_ = 0;
}

void IntervalLineWindow::Add(const IntervalSample& sample, double forget_hi_below) {
  samples_.push_back(sample);
  while (samples_.size() > 1 &&
         (samples_.size() > options_.max_samples || samples_.front().hi < forget_hi_below)) {
    samples_.pop_front();
  }
  ++added_;
  if (samples_.size() < options_.refit_all_below || added_ % options_.refit_every == 0) {
    scratch_.assign(samples_.begin(), samples_.end());
    fit_ = FitIntervalLine(scratch_, sample.x, options_.slope_min, options_.slope_max);
  }
}

}  // namespace selfcal::timing
