// Maps a device clock to host time from receive times, aware of drift: FRI controller time,
// CANopen SYNC counts, GigE Vision / OpenNI2 frame timestamps, the Wenglor picture counter.
//
// Each sample pairs a device timestamp with the host time the message was received. The receive
// time is the true host time of the sample plus a delay that is never negative, so the lower
// envelope of (host - device) over time is the clock offset plus the smallest delay. The filter
// keeps a window of samples and takes, of the lines under every sample, the one highest at the
// window's mean time: an edge of the lower convex hull of (device time, host - device), the linear
// programming estimate of Moon, Skelly and Towsley ("Estimation and removal of clock skew from
// network delay measurements", INFOCOM 1999). Its slope is the drift, optionally bounded (then
// the line is lowered onto the lowest sample so that it never predicts a negative delay). Delays
// that vary (scheduling, a loaded machine, a GigE transfer, a backlog read in one burst after the
// reader stalled) only raise points above the envelope, where they are ignored as long as low
// samples remain on both sides of the mean. Error: the smallest delay of the window (loopback:
// tens of microseconds; GigE: a few ms), plus the drift error times the age of the newest low
// sample.
//
// With never_early the mapping is instead the latest host time consistent with every sample and
// a drift within max_drift (Olson, "A passive solution to the sensor synchronization problem",
// IROS 2010): never earlier than the truth while the drift bound holds, and after a low-delay
// sample late by at most that delay plus max_drift x the time since it. No line is fitted then
// (drift_ppm() stays 0), so a sample costs O(1).
//
// A device clock that stands still or goes back, a receive time far earlier than the line, or
// receive times far later than it for longer than settle_s (a device restart, a PTP step;
// a stalled reader catches up sooner) restart the filter and are reported as a typed ClockJump.
// Not Drake's TimeSyncFilter (an exponential filter of the offset with no drift term).
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "core/timing/clock_jump.h"

namespace selfcal::timing {

struct ClockFilterOptions {
  double window_s = 2.0;        // samples older than this (device time) are forgotten
  std::size_t capacity = 4096;  // samples kept at most (preallocated ring)
  int bins = 8;  // settled once each of this many equal parts of the window holds a sample
  // |host rate / device rate - 1| bound. Unbounded by default: a device time that is a count
  // times a nominal period (CANopen SYNC) runs at whatever rate the real period has. Required
  // (finite) with never_early.
  double max_drift = std::numeric_limits<double>::infinity();
  double min_drift_span_s = 0;  // a shorter window keeps the rate at 1 (too short to tell drift)
  double reset_jump_s = 0.1;    // off the fit by this much: a jump (late: if it lasts settle_s)
  double settle_s = 0.5;        // the window must span this much before we trust it
  std::size_t settle_samples = 50;
  bool never_early = false;  // map to the latest consistent host time (see above)
};

class ClockFilter {
 public:
  ClockFilter() : ClockFilter(ClockFilterOptions{}) {}
  explicit ClockFilter(const ClockFilterOptions& options);

  // Adds a sample: device clock [us], host receive time [us]. Returns the jump that restarted
  // the filter before this sample was added, or kNone.
  ClockJump Add(std::int64_t device_us, std::int64_t host_receive_us);
  // Host time [us] of a device timestamp; meaningful once settled() (or from the first sample,
  // for callers that accept the first samples' larger error).
  std::int64_t ToHost(std::int64_t device_us) const;
  // Add, then ToHost of the same sample: never later than the receive time.
  std::int64_t Map(std::int64_t device_us, std::int64_t host_receive_us);
  void Reset();

  bool settled() const { return settled_; }
  // Host seconds per device second minus 1, in ppm; and host seconds per device second.
  double drift_ppm() const { return slope_ * 1e6; }
  double rate() const { return 1.0 + slope_; }
  // Host minus device time [us] at the newest sample, as mapped.
  double offset_us() const;
  std::size_t size() const { return count_; }
  std::int64_t restarts() const { return restarts_; }  // restarts by a jump (not Reset())

 private:
  struct Pair {
    std::int64_t device_us;
    std::int64_t host_us;
  };
  ClockJump Classify(std::int64_t device_us, std::int64_t host_receive_us);
  void Push(std::int64_t device_us, std::int64_t host_receive_us);
  void Refit();
  bool FitLowerHull();  // false: the hull is steeper than max_drift
  bool EveryBinHoldsASample(double t0, double span);
  // r(t) = host - device - reference_offset at t = device - reference_device, as mapped.
  double OffsetAt(double t) const;
  double T(const Pair& p) const { return static_cast<double>(p.device_us - reference_device_us_); }
  double R(const Pair& p) const {
    return static_cast<double>(p.host_us - p.device_us - reference_offset_us_);
  }
  const Pair& At(std::size_t i) const { return ring_[(head_ + i) % ring_.size()]; }

  ClockFilterOptions options_;
  std::vector<Pair> ring_;
  std::size_t head_ = 0, count_ = 0;
  struct HullPoint {
    double t, r;
  };
  std::vector<HullPoint> hull_;   // FitLowerHull's scratch: the lower hull so far
  std::vector<char> bin_filled_;  // settling: which of the bins holds a sample
  bool settled_ = false;
  bool fitted_ = false;
  std::int64_t reference_device_us_ = 0;  // t = device - reference, to keep doubles exact
  std::int64_t reference_offset_us_ = 0;  // r = host - device - reference_offset
  double intercept_ = 0, slope_ = 0;      // fitted r(t) = intercept + slope * t, in us
  double bound_ = 0;     // never_early: the least upper bound of r at the newest sample
  double newest_t_ = 0;  // t of the newest sample
  std::int64_t restarts_ = 0;
  std::optional<std::int64_t> late_since_us_;  // host time of the first of a run of late samples
};

}  // namespace selfcal::timing
