// Maps the sensor's clock to host time with Olson's passive synchronisation ("A passive solution
// to the sensor synchronization problem", IROS 2010): host receive time = device time + offset +
// latency, latency >= 0, so the lowest observed (host - device) is the best offset estimate. The
// estimate may rise by at most the clock drift bound per unit of device time (a slow sensor clock),
// and falls at once to any lower observation. The mapped time is never later than the receive time.
// Error: the minimum transport latency (a constant bias) plus at most drift bound x time since the
// last low-latency profile.
#pragma once

#include <cstdint>

namespace selfcal::wenglor {

class ClockMapper {
 public:
  explicit ClockMapper(double max_drift_ppm = 200) : max_drift_(max_drift_ppm * 1e-6) {}

  // Returns the host time [us] of the event the device stamped `device_us`, received at `host_us`.
  std::int64_t Map(std::int64_t device_us, std::int64_t host_us);
  void Reset() { initialised_ = false; }
  // Current offset estimate [us]: host = device + offset.
  double offset_us() const { return offset_us_; }

 private:
  double max_drift_;
  bool initialised_ = false;
  std::int64_t last_device_us_ = 0;
  double offset_us_ = 0;
};

}  // namespace selfcal::wenglor
