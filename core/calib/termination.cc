#include "core/calib/termination.h"

#include <cmath>

namespace selfcal::calib {

TerminationCriterion::TerminationCriterion(const CalibrationOptions& options,
                                           const std::atomic<bool>* cancel)
    : epsilon_(options.epsilon),
      step_name_(StepMeasureLabel(options.step_measure)),
      i_max_(options.i_max),
      min_matches_(options.min_matches),
      cancel_(cancel) {}

std::optional<Stop> TerminationCriterion::BeforeIteration(int iteration) const {
  if (iteration > i_max_) {
    return Stop{Termination::kMaxIterations,
                "not converged: i_max = " + std::to_string(i_max_) + " iterations reached"};
  }
  if (Cancelled()) {
    return Stop{Termination::kCancelled, "cancelled before iteration " + std::to_string(iteration)};
  }
  return std::nullopt;
}

std::optional<Stop> TerminationCriterion::AfterMatching(
    int iteration, std::size_t valid_matches, const std::vector<int>& unmatched_scans) const {
  if (valid_matches < min_matches_) {
    std::string message = "iteration " + std::to_string(iteration) + ": " +
                          std::to_string(valid_matches) + " valid matches, fewer than " +
                          std::to_string(min_matches_);
    if (!unmatched_scans.empty()) message += "; scans without any overlap:";
    for (int scan : unmatched_scans) message.append(" ").append(std::to_string(scan));
    return Stop{Termination::kTooFewMatches, message};
  }
  // Matching can take seconds: look again.
  if (Cancelled()) {
    return Stop{Termination::kCancelled, "cancelled during iteration " + std::to_string(iteration)};
  }
  return std::nullopt;
}

std::optional<Stop> TerminationCriterion::AfterSolve(int iteration, bool solved,
                                                     double delta) const {
  if (Cancelled()) {
    return Stop{Termination::kCancelled, "cancelled during iteration " + std::to_string(iteration)};
  }
  if (!solved || !std::isfinite(delta)) {
    return Stop{Termination::kSolverFailed, "iteration " + std::to_string(iteration) +
                                                ": the solver produced non-finite values"};
  }
  return std::nullopt;
}

std::optional<Stop> TerminationCriterion::AfterStep(int iteration, double step) const {
  if (step > epsilon_) return std::nullopt;
  return Stop{Termination::kConverged, std::string(step_name_) + " = " + std::to_string(step) +
                                           " <= epsilon after " + std::to_string(iteration) +
                                           " iterations"};
}

}  // namespace selfcal::calib
