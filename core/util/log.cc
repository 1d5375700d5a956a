#include "core/util/log.h"

#include <cstdio>
#include <vector>

namespace selfcal {

RateLimitedLog::RateLimitedLog(LogSink sink, int burst, Clock::duration window)
    : sink_(std::move(sink)), burst_(burst), window_(window) {}

RateLimitedLog::Line RateLimitedLog::Summary(const std::string& kind, Kind& state,
                                             Clock::duration since) {
  char seconds[32];
  std::snprintf(seconds, sizeof(seconds), "%.1f", std::chrono::duration<double>(since).count());
  Line line{state.level, kind + ": " + std::to_string(state.suppressed) +
                             " more suppressed in the last " + seconds + " s; last: " + state.last};
  state.suppressed = 0;
  state.last.clear();
  return line;
}

void RateLimitedLog::Log(LogLevel level, std::string_view kind, const std::string& message,
                         Clock::time_point now) {
  std::vector<Line> lines;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = kinds_.find(kind);
    if (it == kinds_.end()) {
      it = kinds_.emplace(std::string(kind), Kind{}).first;
      it->second.window_start = now;
    }
    Kind& state = it->second;
    if (now - state.window_start >= window_) {
      if (state.suppressed > 0)
        lines.push_back(Summary(it->first, state, now - state.window_start));
      state.window_start = now;
      state.passed = 0;
    }
    if (state.passed < burst_) {
      ++state.passed;
      lines.push_back({level, message});
    } else {
      ++state.suppressed;
      state.level = level;
      state.last = message;
    }
  }
  if (sink_) {
    for (const Line& line : lines) sink_(line.level, line.text);
  }
}

void RateLimitedLog::Flush(Clock::time_point now) {
  std::vector<Line> lines;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (auto& [kind, state] : kinds_) {
      if (state.suppressed > 0 && now - state.window_start >= window_) {
        lines.push_back(Summary(kind, state, now - state.window_start));
        state.window_start = now;
        state.passed = 0;
      }
    }
  }
  if (sink_) {
    for (const Line& line : lines) sink_(line.level, line.text);
  }
}

void RateLimitedLog::FlushAll() {
  std::vector<Line> lines;
  const Clock::time_point now = Clock::now();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (auto& [kind, state] : kinds_) {
      if (state.suppressed > 0) lines.push_back(Summary(kind, state, now - state.window_start));
    }
  }
  if (sink_) {
    for (const Line& line : lines) sink_(line.level, line.text);
  }
}

}  // namespace selfcal
