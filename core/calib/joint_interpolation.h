// Joint states over time and their linear interpolation to a measurement time (the paper's
// "Data Structure": joint positions are interpolated to the time of every measurement).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/util/expected.h"

namespace selfcal::calib {

// Joint-state samples sorted by time. Positions are sample-major: sample s has joint_count values
// at positions[s * joint_count].
struct JointStateSeries {
  std::size_t joint_count = 0;
  std::vector<std::int64_t> utime;  // host time [us], strictly increasing
  std::vector<double> positions;

  std::size_t size() const { return utime.size(); }
};

// Linear interpolation at `utime` [us, may be fractional] into `out` (joint_count values).
// Both neighbouring samples must exist and lie within `max_gap_us` of the time (an exact sample
// needs only itself); otherwise the error says which neighbour is missing or how far it is.
Status InterpolateJoints(const JointStateSeries& series, double utime, double max_gap_us,
                         std::span<double> out);

// The same without limits, for the engine's latency parameter (joint_correction.h), whose
// shifted times the recording never checked: `utime` clamped to the series, no gap limit.
// The series must not be empty.
void JointsAt(const JointStateSeries& series, double utime, std::span<double> out);

// Joint velocities [per s] at `utime`: the central difference of JointsAt over +- half_window_us,
// the window cut at the series' ends (0 where it is empty). A window of a few samples keeps the
// encoder noise of one sample from dominating the latency's sensitivity.
inline constexpr double kVelocityHalfWindowUs = 5000;
void JointVelocitiesAt(const JointStateSeries& series, double utime, double half_window_us,
                       std::span<double> out);

}  // namespace selfcal::calib
