// Maps a device clock (GigE Vision buffer timestamps, OpenNI2 frame timestamps, V4L2 buffer
// times) to host time, following drift.
//
// Filter ("minimum-delay line"): over a sliding window of (device time, host receive time) pairs,
// the skew is the slope between the least-delayed pair of the older half and that of the newer
// half, and the offset puts the line through the least-delayed pair of the whole window:
// reception is always later than exposure, so the least-delayed pairs bound the true line. Error:
// the remaining bias is the smallest transfer delay in the window (exposure to arrival, a few ms
// over GigE), plus the skew error times the window's age; the residual spread is reported. A device
// clock that jumps (camera restart, PTP step) resets the filter.
#pragma once

#include <cstdint>
#include <vector>

namespace selfcal::camera {

struct DeviceClockOptions {
  std::size_t window = 256;                       // pairs kept (12.8 s at 20 Hz)
  std::int64_t reset_threshold_ns = 500'000'000;  // a prediction off by more resets the filter
};

class DeviceClockMap {
 public:
  explicit DeviceClockMap(DeviceClockOptions options = {});

  // Adds a pair and returns the host time [ns] of `device_ns`; never later than `host_receive_ns`.
  std::int64_t Map(std::int64_t device_ns, std::int64_t host_receive_ns);

  double skew() const { return skew_; }            // host seconds per device second
  std::int64_t resets() const { return resets_; }  // filter restarts (first pair excluded)
  // Spread [ns] of (host - mapped) over the window: how much the transfer delay varies.
  std::int64_t delay_spread_ns() const { return delay_spread_ns_; }

 private:
  void Reset();

  DeviceClockOptions options_;
  std::vector<std::int64_t> device_;  // ring buffers, allocated once
  std::vector<std::int64_t> host_;
  std::size_t count_ = 0;
  std::size_t next_ = 0;
  std::int64_t last_device_ = 0;
  double skew_ = 1.0;
  std::int64_t resets_ = -1;
  std::int64_t delay_spread_ns_ = 0;
};

}  // namespace selfcal::camera
