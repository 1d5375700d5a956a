// Progress of a long command on stderr, so that stdout stays the command's result: a bar redrawn
// in place on a terminal, one line per stage when stderr is a pipe or a log, nothing with
// `selfcal --quiet` (which also keeps info messages out of the log).
#pragma once

#include <string>

namespace selfcal::cli {

class Progress {
 public:
  enum class Mode { kBar, kLines, kQuiet };
  // kQuiet when info messages are not logged (--quiet), else kBar on a terminal, kLines otherwise.
  static Mode ModeFor();

  explicit Progress(Mode mode) : mode_(mode) {}
  ~Progress();  // ends a drawn bar's line
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  // `fraction` of the work done (clamped to [0, 1]) and what it means in `detail`. A bar is
  // redrawn; a line is printed only when `stage` differs from the last one.
  void Update(const std::string& stage, double fraction, const std::string& detail);

 private:
  void EndBar();
  Mode mode_;
  bool drawn_ = false;
  std::string last_stage_;
};

// How far an iterative solver is from its stopping threshold, in [0, 1]: 0 at the first step's
// size, 1 once |step| <= epsilon, in between on a log scale (steps shrink geometrically when an
// ICP converges). Not the iteration count against its maximum, which most runs never reach.
double ConvergenceFraction(double first_step, double step, double epsilon);

}  // namespace selfcal::cli
