// DELIBERATE DEVIATION (docs/engine.md, deviation 19), not in the paper: flying pixels (mixed
// returns) removed before the projection stage. Where a pixel or a beam straddles a depth
// discontinuity, the sensor returns a depth between the two surfaces, a point on neither; the
// paper's noise filter keeps some of them and ICP matches them to a surface up to d_max away.
//
// The test is the "veil" test of laser scan filters: two grid neighbours measured at the same
// instant (a depth image's 4-neighbours; a line profile's or a LiDAR rotation's neighbours along
// the line) whose difference runs within `min_angle` of the view ray, and farther along it than
// the sensor's noise can explain (`sigmas` sigma of the difference of two measurements, sigma =
// sigma_abs + sigma_rel * range), are a jump; both points are removed. So the two sides of every
// depth step and whatever floats between them go, and a surface seen more grazing than
// 90 deg - min_angle goes too (its samples would be as unreliable).
#pragma once

#include <cstdint>
#include <vector>

#include "core/calib/dataset.h"

namespace selfcal::calib {

struct FlyingPixelRule {
  double min_angle_rad = 0;  // 0: nothing is removed
  double sigma_abs = 0;      // m
  double sigma_rel = 0;      // fraction of the range
  double sigmas = 5;
};

// 1 for every point of `dataset` the rule removes, 0 otherwise (points without a measurement
// included); empty when the rule is off.
std::vector<std::uint8_t> FlyingPixels(const Dataset& dataset, const FlyingPixelRule& rule);

}  // namespace selfcal::calib
