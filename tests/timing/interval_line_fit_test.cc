// The interval line fit on synthetic intervals with a known line: quantized readings at random
// phases, too few samples, intervals no line passes; the sliding window over it.
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

TEST(IntervalLineWindow, ForgetsOldSamplesAndRefitsOnItsCadence) {
  IntervalLineWindow window({.slope_min = 0.5,
                             .slope_max = 1.5,
                             .max_samples = 20,
                             .refit_all_below = 5,
                             .refit_every = 3});
  EXPECT_TRUE(window.empty());
  // y = x for 30 samples, then y = x + 100: once the old line's samples are gone, the new fits.
  int refits = 0;
  double previous = 0;
  for (int i = 0; i < 60; ++i) {
    const double x = i;
    const double y = x + (i < 30 ? 0 : 100);
    window.Add({x, y - 0.5, y + 0.5});
    if (window.fit().x_ref != previous || i == 0) ++refits;
    previous = window.fit().x_ref;
  }
  EXPECT_EQ(window.size(), 20u);
  EXPECT_TRUE(window.fit().consistent);
  EXPECT_NEAR(window.fit().At(59), 159, 0.5);
  // Every sample while fewer than 5 are held (4), then every 3rd of the 60 added (19: 6, 9 .. 60).
  EXPECT_EQ(refits, 4 + 19);

  // A time window: samples whose hi is below the bound are forgotten, the newest always kept.
  window.Add({60, 1000, 1001}, /*forget_hi_below=*/1000.5);
  EXPECT_EQ(window.size(), 1u);
  window.Reset();
  EXPECT_TRUE(window.empty());
}

}  // namespace
}  // namespace selfcal::timing
