// Maps a device clock (FRI controller time, CANopen SYNC counts) to host time, aware of drift.
//
// Each sample pairs a device timestamp with the host time the datagram was received. The
// receive time is the true host time of the sample plus a delay that is never negative, so the
// lower envelope of (host - device) over time is the clock offset plus the smallest delay. The
// filter keeps a window of samples, takes the minimum of (host - device) in each of `bins` time
// bins and fits a line through those minima: the slope is the drift, the line the mapping.
// Delays that vary (scheduling, a loaded machine) only raise points above the envelope, where
// they are ignored. Bias: the smallest delay of the window (loopback: tens of microseconds).
// Not Drake's TimeSyncFilter (an exponential filter of the offset with no drift term).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace selfcal {

class ClockFilter {
 public:
  struct Options {
    double window_s = 2.0;  // samples older than this (device time) are forgotten
    int bins = 8;           // lower-envelope points per window
    double settle_s = 0.5;  // the window must span this much before we trust it
    std::size_t settle_samples = 50;
    std::size_t capacity = 4096;  // preallocated ring; > window_s * rate
    double reset_jump_s = 0.1;    // a sample this far off the fit restarts the filter
  };

  ClockFilter() : ClockFilter(Options{}) {}
  explicit ClockFilter(const Options& options);

  // Adds a sample: device clock [us], host receive time [us]. Returns false when the sample
  // restarted the filter (device clock jumped or went backwards).
  bool Add(std::int64_t device_us, std::int64_t host_receive_us);

  bool settled() const { return settled_; }
  // Host time [us] of a device timestamp; meaningful once settled().
  std::int64_t ToHost(std::int64_t device_us) const;
  // Host seconds per device second minus 1, in ppm.
  double drift_ppm() const { return slope_ * 1e6; }
  std::size_t size() const { return count_; }
  void Reset();

 private:
  struct Pair {
    std::int64_t device_us;
    std::int64_t host_us;
  };
  void Refit();
  const Pair& At(std::size_t i) const { return ring_[(head_ + i) % ring_.size()]; }

  Options options_;
  std::vector<Pair> ring_;
  std::size_t head_ = 0, count_ = 0;
  std::vector<double> bin_t_, bin_r_;
  bool settled_ = false;
  bool fitted_ = false;
  std::int64_t reference_device_us_ = 0;  // t = device - reference, to keep doubles exact
  std::int64_t reference_offset_us_ = 0;  // r = host - device - reference_offset
  double intercept_ = 0, slope_ = 0;      // r(t) = intercept + slope * t, in us
};

}  // namespace selfcal
