// Requests refused before they authenticated (too large, undecodable, unsigned, wrongly signed,
// stale, replayed) cost a log line only now and then: the first of each reason is logged with its
// details (escaped by the caller), the rest are counted and logged as one line per reason per
// interval. A flood of forged requests thus costs a few lines a minute and nothing on disk.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>

namespace selfcal::daemon {

class RefusalLog {
 public:
  using Writer = std::function<void(const std::string& line)>;
  RefusalLog(std::int64_t interval_us, Writer write)
      : interval_us_(interval_us), write_(std::move(write)) {}

  // One refusal at `now` [us]: `reason` says why ("wrong signature ..."), `details` what was
  // refused.
  void Count(const std::string& reason, const std::string& details, std::int64_t now);
  // Writes the counts of the intervals that have ended by `now`.
  void Flush(std::int64_t now);
  // Refusals of `reason` since the start.
  std::uint64_t total(const std::string& reason) const;

 private:
  struct Counter {
    bool open = false;          // an interval is running: refusals are counted, not written
    std::int64_t since = 0;     // its start
    std::uint64_t pending = 0;  // counted in it, not yet written
    std::uint64_t total = 0;
  };
  std::int64_t interval_us_;
  Writer write_;
  std::map<std::string, Counter> counters_;
};

// At most `per_interval` events per interval (answers to refused requests: a forger cannot make
// the daemon flood the status channel for him).
class RateLimit {
 public:
  RateLimit(int per_interval, std::int64_t interval_us)
      : per_interval_(per_interval), interval_us_(interval_us) {}
  bool Take(std::int64_t now);

 private:
  int per_interval_;
  std::int64_t interval_us_;
  std::int64_t since_ = 0;
  int taken_ = 0;
  bool started_ = false;
};

}  // namespace selfcal::daemon
