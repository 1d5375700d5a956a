#include "core/calib/joint_interpolation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace selfcal::calib {

namespace {
std::string FormatUs(double utime) {
  return std::to_string(static_cast<std::int64_t>(std::llround(utime)));
}
// Microsecond resolution: a gap just over the limit must not print as the limit itself.
std::string FormatMs(double us) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3f ms", us / 1000.0);
  return text;
}
}  // namespace

Status InterpolateJoints(const JointStateSeries& series, double utime, double max_gap_us,
                         std::span<double> out) {
  const std::size_t n = series.joint_count;
  if (series.size() == 0) return Error{"no joint states at all"};
  // First sample with time >= utime.
  const auto it = std::lower_bound(
      series.utime.begin(), series.utime.end(), utime,
      [](std::int64_t sample, double t) { return static_cast<double>(sample) < t; });
  const std::size_t after = static_cast<std::size_t>(it - series.utime.begin());
  if (after < series.size() && static_cast<double>(series.utime[after]) == utime) {
    std::copy_n(series.positions.begin() + static_cast<std::ptrdiff_t>(after * n), n, out.begin());
    return OkStatus();
  }
  if (after == 0) {
    return Error{"no joint state before utime " + FormatUs(utime) + " (first joint state at " +
                 std::to_string(series.utime.front()) + ")"};
  }
  if (after == series.size()) {
    return Error{"no joint state after utime " + FormatUs(utime) + " (last joint state at " +
                 std::to_string(series.utime.back()) + ")"};
  }
  const std::size_t before = after - 1;
  const double t0 = static_cast<double>(series.utime[before]);
  const double t1 = static_cast<double>(series.utime[after]);
  if (utime - t0 > max_gap_us || t1 - utime > max_gap_us) {
    return Error{"joint states around utime " + FormatUs(utime) + " are " + FormatMs(t1 - t0) +
                 " apart: the one before is " + FormatMs(utime - t0) + " and the one after " +
                 FormatMs(t1 - utime) + " from it (each must lie within " + FormatMs(max_gap_us) +
                 ")"};
  }
  const double w = (utime - t0) / (t1 - t0);
  const double* p0 = series.positions.data() + before * n;
  const double* p1 = series.positions.data() + after * n;
  for (std::size_t j = 0; j < n; ++j) out[j] = (1.0 - w) * p0[j] + w * p1[j];
  return OkStatus();
}

void JointsAt(const JointStateSeries& series, double utime, std::span<double> out) {
  const double first = static_cast<double>(series.utime.front());
  const double last = static_cast<double>(series.utime.back());
  const Status status = InterpolateJoints(series, std::clamp(utime, first, last),
                                          std::numeric_limits<double>::infinity(), out);
  (void)status;  // within the series and without a gap limit it cannot fail
}

void JointVelocitiesAt(const JointStateSeries& series, double utime, double half_window_us,
                       std::span<double> out) {
  const std::size_t n = series.joint_count;
  const double t0 = std::max(utime - half_window_us, static_cast<double>(series.utime.front()));
  const double t1 = std::min(utime + half_window_us, static_cast<double>(series.utime.back()));
  if (!(t1 > t0)) {
    std::fill(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(n), 0.0);
    return;
  }
  constexpr std::size_t kOnStack = 32;  // called once per knot: no allocation for real arms
  double stack[2 * kOnStack];
  std::vector<double> heap(n > kOnStack ? 2 * n : 0);
  double* q0 = n > kOnStack ? heap.data() : stack;
  double* q1 = q0 + n;
  JointsAt(series, t0, std::span<double>(q0, n));
  JointsAt(series, t1, std::span<double>(q1, n));
  const double per_second = 1e6 / (t1 - t0);
  for (std::size_t j = 0; j < n; ++j) out[j] = (q1[j] - q0[j]) * per_second;
}

}  // namespace selfcal::calib
