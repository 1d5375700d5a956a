// Anderson acceleration of a fixed-point iteration (core/calib/anderson_acceleration.h): on a
// slowly contracting linear map it reaches the fixed point in a few steps where the plain
// iteration needs hundreds; it waits for a run of shorter and shorter steps; its safeguard drops
// a point that made the step grow or lost matches; a point that was never matched is never the
// result.
#include "core/calib/anderson_acceleration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace selfcal::calib {
namespace {

// G(x) = A x + b on the free entries 0 and 2 of a 3-vector (entry 1 is not free and stays 7):
// eigenvalues 0.97 and 0.5 on rotated axes, fixed point (1, 7, -2).
std::vector<double> G(const std::vector<double>& x) {
  const double u = x[0] - 1.0, v = x[2] + 2.0;
  const double a = 0.735 * u + 0.235 * v, c = 0.235 * u + 0.735 * v;
  return {1.0 + a, 7.0, -2.0 + c};
}

// The valid matches of every ICP iteration, unless a test says otherwise.
constexpr std::size_t kMatches = 100000;

double Distance(const std::vector<double>& a, const std::vector<double>& b) {
  return std::hypot(a[0] - b[0], a[2] - b[2]);
}

// Iterations until the step is below 1e-10, at most 1000.
int IterationsToConverge(int memory, std::vector<double>* result = nullptr) {
  AndersonAcceleration acceleration(memory, {0, 2}, Eigen::MatrixXd::Identity(2, 2));
  std::vector<double> x = {5.0, 7.0, 3.0};
  for (int iteration = 1; iteration <= 1000; ++iteration) {
    std::vector<double> g = G(x);
    const double step = Distance(g, x);
    if (step < 1e-10) {
      if (result != nullptr) *result = g;
      return iteration;
    }
    x = acceleration.Next(x, std::move(g), step, kMatches);
    EXPECT_EQ(x[1], 7.0);
  }
  return 1000;
}

TEST(AndersonAcceleration, ReachesTheFixedPointOfASlowContractionInAFewSteps) {
  std::vector<double> plain, accelerated;
  const int plain_iterations = IterationsToConverge(0, &plain);
  const int accelerated_iterations = IterationsToConverge(5, &accelerated);
  EXPECT_GT(plain_iterations, 500);
  EXPECT_LE(accelerated_iterations, 10);
  EXPECT_NEAR(accelerated[0], 1.0, 1e-9);
  EXPECT_NEAR(accelerated[2], -2.0, 1e-9);
  EXPECT_NEAR(plain[0], 1.0, 1e-8);
}

TEST(AndersonAcceleration, WithoutMemoryItIsThePlainIteration) {
  AndersonAcceleration off(0, {0, 2}, Eigen::MatrixXd::Identity(2, 2));
  const std::vector<double> x = {5.0, 7.0, 3.0};
  EXPECT_EQ(off.Next(x, G(x), 1.0, kMatches), G(x));
  EXPECT_EQ(off.Next(G(x), G(G(x)), 0.9, kMatches), G(G(x)));
  EXPECT_EQ(off.accelerated(), 0);
}

// Plain iterations of G from (5, 7, 3) until the acceleration hands out a point; `last_g` is
// the last plain G value before it.
std::vector<double> FirstAcceleratedPoint(AndersonAcceleration& acceleration,
                                          std::vector<double>* last_g) {
  std::vector<double> x = {5.0, 7.0, 3.0};
  for (int iteration = 0; iteration < 10; ++iteration) {
    const std::vector<double> g = G(x);
    std::vector<double> next = acceleration.Next(x, g, Distance(g, x), kMatches);
    if (next != g) {
      *last_g = g;
      return next;
    }
    x = next;
  }
  ADD_FAILURE() << "no accelerated point in 10 iterations";
  return x;
}

TEST(AndersonAcceleration, WaitsForARunOfShorterAndShorterPlainSteps) {
  AndersonAcceleration acceleration(5, {0, 2}, Eigen::MatrixXd::Identity(2, 2));
  std::vector<double> x = {5.0, 7.0, 3.0};
  // Steps 1.0, 0.9, then 1.2 (longer: a new run starts there), 1.0, then 0.8: the third of the
  // run 1.2, 1.0, 0.8.
  const double steps[] = {1.0, 0.9, 1.2, 1.0};
  for (double step : steps) {
    const std::vector<double> g = G(x);
    EXPECT_EQ(acceleration.Next(x, g, step, kMatches), g)
        << "accelerated before a run of 3 at " << step;
    x = g;
  }
  const std::vector<double> g = G(x);
  EXPECT_NE(acceleration.Next(x, g, 0.8, kMatches), g);
  EXPECT_EQ(acceleration.accelerated(), 1);
}

TEST(AndersonAcceleration, APointThatMadeTheStepGrowIsDroppedForTheLastPlainOne) {
  AndersonAcceleration acceleration(5, {0, 2}, Eigen::MatrixXd::Identity(2, 2));
  std::vector<double> last_g;
  const std::vector<double> a = FirstAcceleratedPoint(acceleration, &last_g);
  EXPECT_EQ(acceleration.accelerated(), 1);
  // The ICP step from `a` (as if its matches were worse) is longer than the step before it.
  EXPECT_EQ(acceleration.Next(a, {0.0, 7.0, 0.0}, 10.0, kMatches), last_g);
  EXPECT_EQ(acceleration.rejected(), 1);
  // ... and it waits for a new run of shorter steps before it accelerates again.
  std::vector<double> x = last_g;
  for (int plain = 0; plain < AndersonAcceleration::kContracting - 1; ++plain) {
    const std::vector<double> g = G(x);
    EXPECT_EQ(acceleration.Next(x, g, Distance(g, x), kMatches), g);
    x = g;
  }
}

TEST(AndersonAcceleration, APointThatLostMatchesIsDroppedHoweverShortItsStep) {
  AndersonAcceleration acceleration(5, {0, 2}, Eigen::MatrixXd::Identity(2, 2));
  std::vector<double> last_g;
  const std::vector<double> a = FirstAcceleratedPoint(acceleration, &last_g);
  const std::vector<double> ga = G(a);
  const double step = Distance(ga, a);  // shorter than the plain step before: kept on its own
  const auto fewer = static_cast<std::size_t>(0.97 * static_cast<double>(kMatches));
  EXPECT_EQ(acceleration.Next(a, ga, step, fewer), last_g);
  EXPECT_EQ(acceleration.rejected(), 1);
  // Within the share, the same point is kept.
  AndersonAcceleration again(5, {0, 2}, Eigen::MatrixXd::Identity(2, 2));
  const std::vector<double> b = FirstAcceleratedPoint(again, &last_g);
  const auto slightly_fewer = static_cast<std::size_t>(0.99 * static_cast<double>(kMatches));
  EXPECT_NE(again.Next(b, G(b), Distance(G(b), b), slightly_fewer), last_g);
  EXPECT_EQ(again.rejected(), 0);
}

TEST(AndersonAcceleration, AnAcceleratedPointNeverMatchedIsNotTheResult) {
  AndersonAcceleration acceleration(5, {0, 2}, Eigen::MatrixXd::Identity(2, 2));
  std::vector<double> last_g;
  const std::vector<double> a = FirstAcceleratedPoint(acceleration, &last_g);
  EXPECT_EQ(acceleration.Settled(a), last_g);  // stopped (i_max, cancelled) before matching at a
  const std::vector<double> ga = G(a);
  EXPECT_EQ(acceleration.Settled(ga), ga);  // stopped after matching and solving at a
}

// A free entry with a least value (a joint's compliance, LowerBounds of joint_correction.h): the
// accelerated point keeps to it; the other entries are the combination's.
TEST(AndersonAcceleration, AnAcceleratedPointKeepsToTheLowerBounds) {
  AndersonAcceleration unbounded(5, {0, 2}, Eigen::MatrixXd::Identity(2, 2));
  AndersonAcceleration bounded(5, {0, 2}, Eigen::MatrixXd::Identity(2, 2),
                               {1.5, -std::numeric_limits<double>::infinity()});
  std::vector<double> last_g;
  const std::vector<double> a = FirstAcceleratedPoint(unbounded, &last_g);
  EXPECT_GT(last_g[0], 1.5);  // the plain iteration is still above the bound
  EXPECT_LT(a[0], 1.5);       // the combination jumps below it, to the fixed point's 1
  const std::vector<double> b = FirstAcceleratedPoint(bounded, &last_g);
  EXPECT_EQ(b[0], 1.5);
  EXPECT_EQ(b[2], a[2]);
}

}  // namespace
}  // namespace selfcal::calib
