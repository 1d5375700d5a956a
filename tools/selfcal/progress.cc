#include "tools/selfcal/progress.h"

#include <spdlog/spdlog.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace selfcal::cli {

namespace {

constexpr int kBarWidth = 30;

// The terminal's width: a bar line longer than that would wrap, and \r would not return to its
// start.
std::size_t TerminalColumns() {
  winsize size{};
  if (ioctl(STDERR_FILENO, TIOCGWINSZ, &size) == 0 && size.ws_col > 0) return size.ws_col;
  return 80;
}

}  // namespace

Progress::Mode Progress::ModeFor() {
  if (!spdlog::should_log(spdlog::level::info)) return Mode::kQuiet;
  return isatty(STDERR_FILENO) == 1 ? Mode::kBar : Mode::kLines;
}

Progress::~Progress() { EndBar(); }

void Progress::EndBar() {
  if (drawn_) std::fputc('\n', stderr);
}

void Progress::Update(const std::string& stage, double fraction, const std::string& detail) {
  const bool new_stage = stage != last_stage_;
  last_stage_ = stage;
  if (mode_ == Mode::kQuiet) return;
  if (mode_ == Mode::kLines) {
    if (new_stage) std::fprintf(stderr, "progress: %s: %s\n", stage.c_str(), detail.c_str());
    return;
  }
  const double clamped = std::isfinite(fraction) ? std::clamp(fraction, 0.0, 1.0) : 0.0;
  const auto filled = static_cast<std::size_t>(std::lround(clamped * kBarWidth));
  char head[64];
  std::snprintf(head, sizeof(head), "[%-*s] %3.0f%% ", kBarWidth, std::string(filled, '#').c_str(),
                100 * clamped);
  std::string line = head + stage + ": " + detail;
  line.resize(std::min(line.size(), TerminalColumns() - 1));
  // \x1b[K clears what a longer previous line left on the right.
  std::fprintf(stderr, "\r%s\x1b[K", line.c_str());
  std::fflush(stderr);
  drawn_ = true;
}

double ConvergenceFraction(double first_step, double step, double epsilon) {
  if (!(epsilon > 0) || !std::isfinite(step)) return 0;
  if (step <= epsilon) return 1;
  if (!(first_step > epsilon) || step >= first_step) return 0;
  return std::log(first_step / step) / std::log(first_step / epsilon);
}

}  // namespace selfcal::cli
