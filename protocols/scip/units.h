// SCIP 2.0 steps and millimetres to SI (protocols.md 1.6): the one place a Hokuyo's mirror steps
// become angles and its range values become metres.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "protocols/scip/commands.h"
#include "protocols/scip/replies.h"

namespace selfcal::scip {

// Angle [rad] of mirror step `step`: (step - AFRT) * 2 pi / ARES, from +x towards +y.
double StepAngle(const Parameters& parameters, int step);
// Angle [rad] between two consecutive values of a scan of `request` (clustered steps).
double ValueIncrement(const Parameters& parameters, const ScanRequest& request);
// The mirror's rotation period [us] from SCAN [rpm].
double RotationPeriodUs(const Parameters& parameters);

// Range values [mm] to metres; values below DMIN are error codes (no echo, too bright, ...) and
// values above DMAX invalid: both NaN. `ranges_m` is resized to the number of values.
void RangesToMetres(const Parameters& parameters, std::span<const std::uint32_t> ranges_mm,
                    std::vector<float>& ranges_m);

}  // namespace selfcal::scip
