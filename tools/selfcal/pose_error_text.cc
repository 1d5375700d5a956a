#include "tools/selfcal/pose_error_text.h"

#include <cstdio>
#include <numbers>

namespace selfcal::cli {

std::string SampleSetText(std::size_t samples, std::uint64_t seed) {
  return std::to_string(samples) + " configurations (seed " + std::to_string(seed) + ")";
}

std::string PoseErrorText(const PoseErrorStats& stats) {
  constexpr double kMmPerM = 1000.0;
  constexpr double kDegPerRad = 180.0 / std::numbers::pi;
  char text[160];
  std::snprintf(text, sizeof text,
                "position rms %9.3f mm  max %9.3f mm   orientation rms %8.4f deg  max %8.4f deg",
                stats.rms_position_m * kMmPerM, stats.max_position_m * kMmPerM,
                stats.rms_orientation_rad * kDegPerRad, stats.max_orientation_rad * kDegPerRad);
  return text;
}

}  // namespace selfcal::cli
