#include "protocols/scip/units.h"

#include <algorithm>
#include <limits>
#include <numbers>

namespace selfcal::scip {

double StepAngle(const Parameters& parameters, int step) {
  return 2 * std::numbers::pi * (step - parameters.front_step) / parameters.steps_per_rotation;
}

double ValueIncrement(const Parameters& parameters, const ScanRequest& request) {
  return 2 * std::numbers::pi * std::max(1, request.cluster) / parameters.steps_per_rotation;
}

double RotationPeriodUs(const Parameters& parameters) { return 60e6 / parameters.rotation_rpm; }

void RangesToMetres(const Parameters& parameters, std::span<const std::uint32_t> ranges_mm,
                    std::vector<float>& ranges_m) {
  const auto min_mm = static_cast<std::uint32_t>(parameters.min_range_mm);
  const auto max_mm = static_cast<std::uint32_t>(parameters.max_range_mm);
  ranges_m.resize(ranges_mm.size());
  for (std::size_t i = 0; i < ranges_mm.size(); ++i) {
    const std::uint32_t mm = ranges_mm[i];
    ranges_m[i] = (mm < min_mm || mm > max_mm) ? std::numeric_limits<float>::quiet_NaN()
                                               : static_cast<float>(mm) * 1e-3f;
  }
}

}  // namespace selfcal::scip
