// The one log-level and log-sink type. Library code never prints: it logs through the sink its
// owner gave it (the programs pass protocols/program's spdlog sink; tests collect messages).
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <string_view>

namespace selfcal {

enum class LogLevel { kDebug, kInfo, kWarning, kError };

using LogSink = std::function<void(LogLevel level, const std::string& message)>;

// A sink for messages that can repeat without bound (a device sending junk, a reconnect loop):
// of each kind, at most `burst` messages pass per `window`; the others are counted and reported
// as one line ("<kind>: N more suppressed in the last S s; last: ...") once the window is over,
// so a flood neither fills the journal nor slows the loop that logs. Thread-safe.
class RateLimitedLog {
 public:
  using Clock = std::chrono::steady_clock;

  explicit RateLimitedLog(LogSink sink, int burst = 5,
                          Clock::duration window = std::chrono::seconds(10));

  // `kind` names what repeats ("rejected block"); messages of one kind may differ in details.
  void Log(LogLevel level, std::string_view kind, const std::string& message) {
    Log(level, kind, message, Clock::now());
  }
  void Log(LogLevel level, std::string_view kind, const std::string& message,
           Clock::time_point now);
  // Reports the suppressed counts of the kinds whose window is over (call it now and then, so a
  // flood that stopped is still summed up).
  void Flush(Clock::time_point now);
  void Flush() { Flush(Clock::now()); }
  // Reports every suppressed count, over or not (before the owner stops).
  void FlushAll();

 private:
  struct Kind {
    Clock::time_point window_start;
    int passed = 0;
    std::int64_t suppressed = 0;
    LogLevel level = LogLevel::kInfo;
    std::string last;
  };
  struct Line {
    LogLevel level;
    std::string text;
  };
  static Line Summary(const std::string& kind, Kind& state, Clock::duration since);

  LogSink sink_;
  int burst_;
  Clock::duration window_;
  std::mutex mutex_;
  std::map<std::string, Kind, std::less<>> kinds_;
};

}  // namespace selfcal
