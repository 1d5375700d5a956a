// The stop rule of Algorithm 1 and the engine's early stops, in the order Calibrate() asks them.
#include "core/calib/termination.h"

#include <gtest/gtest.h>

#include <cmath>

namespace selfcal::calib {
namespace {

CalibrationOptions Options() {
  CalibrationOptions options;
  options.epsilon = 1e-4;
  options.i_max = 3;
  options.min_matches = 100;
  return options;
}

TEST(TerminationCriterion, StopsAfterIMaxIterations) {
  const TerminationCriterion criterion(Options(), nullptr);
  EXPECT_FALSE(criterion.BeforeIteration(1));
  EXPECT_FALSE(criterion.BeforeIteration(3));
  const auto stop = criterion.BeforeIteration(4);
  ASSERT_TRUE(stop);
  EXPECT_EQ(stop->termination, Termination::kMaxIterations);
  EXPECT_EQ(stop->message, "not converged: i_max = 3 iterations reached");
}

TEST(TerminationCriterion, ConvergesWhenTheStepIsAtMostEpsilon) {
  const TerminationCriterion criterion(Options(), nullptr);
  EXPECT_FALSE(criterion.AfterStep(2, 1.01e-4));
  const auto stop = criterion.AfterStep(2, 1e-4);
  ASSERT_TRUE(stop);
  EXPECT_EQ(stop->termination, Termination::kConverged);
  EXPECT_NE(stop->message.find("after 2 iterations"), std::string::npos) << stop->message;
}

TEST(TerminationCriterion, TooFewMatchesNamesTheScansWithoutOverlap) {
  const TerminationCriterion criterion(Options(), nullptr);
  EXPECT_FALSE(criterion.AfterMatching(1, 100, {}));
  const auto stop = criterion.AfterMatching(2, 99, {4, 7});
  ASSERT_TRUE(stop);
  EXPECT_EQ(stop->termination, Termination::kTooFewMatches);
  EXPECT_EQ(stop->message,
            "iteration 2: 99 valid matches, fewer than 100; scans without any overlap: 4 7");
  EXPECT_EQ(criterion.AfterMatching(2, 0, {})->message,
            "iteration 2: 0 valid matches, fewer than 100");
}

TEST(TerminationCriterion, AFailedOrNonFiniteSolveStops) {
  const TerminationCriterion criterion(Options(), nullptr);
  EXPECT_FALSE(criterion.AfterSolve(1, true, 0.5));
  EXPECT_EQ(criterion.AfterSolve(1, false, 0.5)->termination, Termination::kSolverFailed);
  EXPECT_EQ(criterion.AfterSolve(1, true, std::nan(""))->termination, Termination::kSolverFailed);
}

TEST(TerminationCriterion, CancellationIsSeenAtEveryPointButIMaxComesFirst) {
  std::atomic<bool> cancel{true};
  const TerminationCriterion criterion(Options(), &cancel);
  EXPECT_EQ(criterion.BeforeIteration(2)->message, "cancelled before iteration 2");
  EXPECT_EQ(criterion.AfterMatching(2, 1000, {})->message, "cancelled during iteration 2");
  // Too few matches is the more useful answer when both hold.
  EXPECT_EQ(criterion.AfterMatching(2, 10, {})->termination, Termination::kTooFewMatches);
  EXPECT_EQ(criterion.AfterSolve(2, false, 0.5)->termination, Termination::kCancelled);
  EXPECT_EQ(criterion.BeforeIteration(4)->termination, Termination::kMaxIterations);
  cancel = false;
  EXPECT_FALSE(criterion.BeforeIteration(2));
}

}  // namespace
}  // namespace selfcal::calib
