// Steps to angles, SCAN to a period and millimetres to metres, on the UTM-30LX-EW geometry of
// protocols.md 1.6 (ARES 1440, AMIN 0, AMAX 1080, AFRT 540, DMIN 23, DMAX 60000, 2400 rpm).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "protocols/scip/units.h"

namespace selfcal::scip {
namespace {

Parameters Utm30lx() {
  Parameters p;
  p.model = "UTM-30LX-EW";
  p.min_range_mm = 23;
  p.max_range_mm = 60000;
  p.steps_per_rotation = 1440;
  p.first_step = 0;
  p.last_step = 1080;
  p.front_step = 540;
  p.rotation_rpm = 2400;
  return p;
}

TEST(ScipUnits, StepsBecomeAnglesFromTheFrontStep) {
  const Parameters p = Utm30lx();
  EXPECT_DOUBLE_EQ(StepAngle(p, 540), 0.0);
  EXPECT_DOUBLE_EQ(StepAngle(p, 0), -0.75 * std::numbers::pi);    // -135 degrees
  EXPECT_DOUBLE_EQ(StepAngle(p, 1080), 0.75 * std::numbers::pi);  // +135 degrees
  EXPECT_DOUBLE_EQ(StepAngle(p, 900), std::numbers::pi / 2);
  const double step = 2 * std::numbers::pi / 1440;
  EXPECT_DOUBLE_EQ(ValueIncrement(p, {ScanType::kMD, 0, 1080, 1}), step);
  EXPECT_DOUBLE_EQ(ValueIncrement(p, {ScanType::kMD, 0, 1080, 0}), step);  // 0 means 1
  EXPECT_DOUBLE_EQ(ValueIncrement(p, {ScanType::kMD, 0, 1080, 3}), 3 * step);
  EXPECT_DOUBLE_EQ(RotationPeriodUs(p), 25000.0);  // 2400 rpm = 40 Hz
}

TEST(ScipUnits, MillimetresBecomeMetresAndErrorCodesNaN) {
  const Parameters p = Utm30lx();
  const std::vector<std::uint32_t> mm = {0, 1, 22, 23, 1234, 60000, 60001, 262143};
  std::vector<float> m(3, 7.0f);  // resized, not appended to
  RangesToMetres(p, mm, m);
  ASSERT_EQ(m.size(), mm.size());
  EXPECT_TRUE(std::isnan(m[0]));  // error codes below DMIN
  EXPECT_TRUE(std::isnan(m[1]));
  EXPECT_TRUE(std::isnan(m[2]));
  EXPECT_FLOAT_EQ(m[3], 0.023f);
  EXPECT_FLOAT_EQ(m[4], 1.234f);
  EXPECT_FLOAT_EQ(m[5], 60.0f);
  EXPECT_TRUE(std::isnan(m[6]));  // beyond DMAX
  EXPECT_TRUE(std::isnan(m[7]));
  RangesToMetres(p, {}, m);
  EXPECT_TRUE(m.empty());
}

}  // namespace
}  // namespace selfcal::scip
