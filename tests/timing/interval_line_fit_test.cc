// The interval line fit on synthetic intervals with a known line: quantized readings at random
// phases, too few samples, intervals no line passes.
#include "core/timing/interval_line_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace selfcal::timing {
namespace {

TEST(IntervalLineFit, RecoversALineFromIntervalsAtRandomPhases) {
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> phase(0, 1);
  const double a = 12.3456;
  const double b = 1.00005;
  std::vector<IntervalSample> samples;
  for (int i = 0; i < 200; ++i) {
    const double x = i * 10.0 + phase(random);
    const double y = a + b * x;
    const double lo = std::floor(y);  // a quantized reading: y lies in [floor, floor + 1)
    samples.push_back({x, lo, lo + 1});
  }
  const auto fit = FitIntervalLine(samples, 1000.0, 0.999, 1.001);
  EXPECT_TRUE(fit.consistent);
  EXPECT_NEAR(fit.At(1000.0), a + b * 1000.0, 0.02);
  EXPECT_NEAR(fit.slope, b, 5e-6);
  EXPECT_GT(fit.margin, 0);
}

TEST(IntervalLineFit, FewSamplesStayAtThePriorCentre) {
  // Three clustered samples constrain the slope hardly at all: the middle of the prior is kept.
  const std::vector<IntervalSample> samples = {{0, 10, 11}, {0.1, 10, 11}, {0.2, 10.1, 11}};
  const auto fit = FitIntervalLine(samples, 0.2, 0.99, 1.01);
  EXPECT_NEAR(fit.slope, 1.0, 1e-3);
  EXPECT_TRUE(fit.consistent);
}

TEST(IntervalLineFit, InconsistentIntervalsGiveTheMinimaxLine) {
  const std::vector<IntervalSample> samples = {{0, 0, 1}, {1, 3, 4}, {2, 0, 1}};
  const auto fit = FitIntervalLine(samples, 1.0, -1, 1);
  EXPECT_FALSE(fit.consistent);
  EXPECT_LT(fit.margin, 0);
}

}  // namespace
}  // namespace selfcal::timing
