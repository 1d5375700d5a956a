#include "protocols/camera/device_clock.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace selfcal::camera {

DeviceClockMap::DeviceClockMap(DeviceClockOptions options)
    : options_(options),
      device_(std::max<std::size_t>(options.window, 2)),
      host_(std::max<std::size_t>(options.window, 2)) {}

void DeviceClockMap::Reset() {
  count_ = 0;
  next_ = 0;
  skew_ = 1.0;
  ++resets_;
}

std::int64_t DeviceClockMap::Map(std::int64_t device_ns, std::int64_t host_receive_ns) {
  if (count_ == 0) {
    Reset();
  } else {
    // Predict with the current line before adding: a device clock that went backwards or far off
    // the line means the device restarted (or its PTP clock stepped).
    const std::size_t newest = (next_ + device_.size() - 1) % device_.size();
    const double predicted = static_cast<double>(host_[newest]) +
                             skew_ * static_cast<double>(device_ns - device_[newest]);
    if (device_ns <= last_device_ || std::abs(predicted - static_cast<double>(host_receive_ns)) >
                                         static_cast<double>(options_.reset_threshold_ns)) {
      Reset();
    }
  }
  last_device_ = device_ns;
  device_[next_] = device_ns;
  host_[next_] = host_receive_ns;
  next_ = (next_ + 1) % device_.size();
  count_ = std::min(count_ + 1, device_.size());

  // Skew: the slope between the least-delayed pair of the older half of the window and that of
  // the newer half (the lower envelope). A least-squares slope over a few seconds would follow
  // the delay jitter; the minima do not.
  if (count_ == device_.size()) {
    const std::size_t half = count_ / 2;
    const auto least_delayed = [&](std::size_t first, std::size_t n) {
      std::size_t best = (next_ + first) % count_;
      for (std::size_t k = 0; k < n; ++k) {
        const std::size_t i = (next_ + first + k) % count_;  // oldest first
        if (host_[i] - device_[i] < host_[best] - device_[best]) best = i;
      }
      return best;
    };
    const std::size_t older = least_delayed(0, half);
    const std::size_t newer = least_delayed(half, count_ - half);
    const double span = static_cast<double>(device_[newer] - device_[older]);
    if (span > 1e9) {  // at least a second apart
      skew_ = std::clamp(static_cast<double>(host_[newer] - host_[older]) / span, 1.0 - 1e-3,
                         1.0 + 1e-3);
    }
  }
  double min_delay = std::numeric_limits<double>::max();
  double max_delay = std::numeric_limits<double>::lowest();
  for (std::size_t i = 0; i < count_; ++i) {
    // Delay of pair i if the line passed through this pair: host_i - (host_now + skew (d_i -
    // d_now)).
    const double delay = static_cast<double>(host_[i] - host_receive_ns) -
                         skew_ * static_cast<double>(device_[i] - device_ns);
    min_delay = std::min(min_delay, delay);
    max_delay = std::max(max_delay, delay);
  }
  delay_spread_ns_ = static_cast<std::int64_t>(max_delay - min_delay);
  // The line through the least-delayed pair, evaluated at this pair's device time.
  const std::int64_t mapped = host_receive_ns + static_cast<std::int64_t>(std::llround(min_delay));
  return std::min(mapped, host_receive_ns);
}

}  // namespace selfcal::camera
