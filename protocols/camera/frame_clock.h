// The clock filter's parameters for camera frames (GigE Vision buffer timestamps, OpenNI2 frame
// timestamps): frames arrive at 10..60 Hz after a transfer of a few to tens of milliseconds
// whose length varies with the bus load, so the window is long and the drift is the slope of the
// lower hull of its receive times (timing::ClockFilter, docs/cameras.md).
#pragma once

#include <limits>

#include "core/timing/clock_filter.h"

namespace selfcal::camera {

inline timing::ClockFilterOptions FrameClockOptions() {
  timing::ClockFilterOptions options;
  options.window_s = std::numeric_limits<double>::infinity();  // by count: 12.8 s at 20 Hz
  options.capacity = 256;
  options.bins = 2;
  options.max_drift = 1e-3;
  // Least-delayed frames a second apart or more: a shorter span would follow the delay jitter.
  options.min_drift_span_s = 1.0;
  options.reset_jump_s = 0.5;  // a camera restart or a PTP step
  return options;
}

}  // namespace selfcal::camera
