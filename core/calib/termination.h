// When Algorithm 1 stops: "until |delta k_opt| <= epsilon" (the step measured as
// CalibrationOptions::step_measure says: docs/engine.md, deviation 18), bounded by i_max, and the
// ways the engine ends an iteration early without crashing: cancellation, too few matches, a failed
// solve. Calibrate() asks it at the three points of an iteration where it may stop.
#pragma once

#include <atomic>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "core/calib/calibrate.h"

namespace selfcal::calib {

struct Stop {
  Termination termination;
  std::string message;  // why, in words (CalibrationResult::message)
};

class TerminationCriterion {
 public:
  // `cancel` may be null (never cancelled).
  TerminationCriterion(const CalibrationOptions& options, const std::atomic<bool>* cancel);

  // Before iteration `iteration` (from 1): i_max iterations done, or cancelled.
  std::optional<Stop> BeforeIteration(int iteration) const;
  // After matching: fewer than min_matches valid matches (`unmatched_scans`: the scan_index of
  // every fit scan without a match, named in the message), or cancelled while matching.
  std::optional<Stop> AfterMatching(int iteration, std::size_t valid_matches,
                                    const std::vector<int>& unmatched_scans) const;
  // After the solve, before its step is taken: cancelled during the solve (the step was cut
  // short), or the solver failed or moved by a non-finite |delta k_hat|. A stop here discards
  // the step.
  std::optional<Stop> AfterSolve(int iteration, bool solved, double delta) const;
  // After the step is taken: the step <= epsilon, the paper's stop.
  std::optional<Stop> AfterStep(int iteration, double step) const;

 private:
  bool Cancelled() const { return cancel_ != nullptr && cancel_->load(); }

  double epsilon_;
  const char* step_name_;  // what the step is, for the message
  int i_max_;
  std::size_t min_matches_;
  const std::atomic<bool>* cancel_;
};

}  // namespace selfcal::calib
