// Where the simulated sensor's ranges come from. The simulator asks once per scan, with the
// scan's true timing, so a source may move a robot and cast rays (core/sim) or return a pattern.
#pragma once

#include <cstdint>
#include <span>

namespace selfcal::sim_scip {

// The truth about one scan, as the simulated device measured it.
struct ScanTiming {
  std::uint32_t timestamp_ms = 0;  // the 24-bit counter value the device reports for this scan
  double device_time_us = 0;       // device clock at step 0 (continuous, before the floor)
  double host_time_us = 0;         // host CLOCK_MONOTONIC [us] at step 0
  double host_us_per_step = 0;     // host time between two steps
  int first_step = 0;              // the request's first and last step (before clustering)
  int last_step = 0;
  int front_step = 0;          // AFRT: step of angle 0
  int steps_per_rotation = 0;  // ARES
  int cluster = 1;
};

class RangeSource {
 public:
  virtual ~RangeSource() = default;
  // Fills one range [mm] (and one intensity) per value of the request; step i of the request
  // is measured at host_time_us + (first_step + i) * host_us_per_step. 0..DMIN-1 are error codes.
  virtual void Ranges(const ScanTiming& timing, std::span<std::uint32_t> ranges_mm,
                      std::span<std::uint32_t> intensities) = 0;
};

// A deterministic pattern that tests can recompute from the published device timestamp:
// range(step, ts) = 100 + (step * 37 + ts * 11) % 29000 mm, intensity = 1000 + step.
class PatternRangeSource final : public RangeSource {
 public:
  static std::uint32_t Range(int step, std::uint32_t timestamp_ms) {
    return 100u + static_cast<std::uint32_t>((static_cast<std::uint64_t>(step) * 37u +
                                              static_cast<std::uint64_t>(timestamp_ms) * 11u) %
                                             29000u);
  }
  void Ranges(const ScanTiming& timing, std::span<std::uint32_t> ranges_mm,
              std::span<std::uint32_t> intensities) override {
    const int cluster = timing.cluster <= 1 ? 1 : timing.cluster;
    for (std::size_t i = 0; i < ranges_mm.size(); ++i) {
      const int step = timing.first_step + static_cast<int>(i) * cluster;
      ranges_mm[i] = Range(step, timing.timestamp_ms);
      if (i < intensities.size()) intensities[i] = 1000u + static_cast<std::uint32_t>(step);
    }
  }
};

}  // namespace selfcal::sim_scip
