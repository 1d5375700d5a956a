#include "drivers/wenglor/clock_mapper.h"

#include <algorithm>
#include <cmath>

namespace selfcal::wenglor {

std::int64_t ClockMapper::Map(std::int64_t device_us, std::int64_t host_us) {
  const double observed = static_cast<double>(host_us - device_us);
  if (!initialised_) {
    initialised_ = true;
    offset_us_ = observed;
  } else {
    const double elapsed =
        static_cast<double>(std::max<std::int64_t>(0, device_us - last_device_us_));
    offset_us_ = std::min(observed, offset_us_ + max_drift_ * elapsed);
  }
  last_device_us_ = device_us;
  return device_us + static_cast<std::int64_t>(std::floor(offset_us_));
}

}  // namespace selfcal::wenglor
