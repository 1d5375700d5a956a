#include "daemon/refusal_log.h"

#include <cstdio>

namespace selfcal::daemon {

void RefusalLog::Count(const std::string& reason, const std::string& details, std::int64_t now) {
  Counter& counter = counters_[reason];
  ++counter.total;
  if (counter.open) {
    ++counter.pending;
    return;
  }
  counter.open = true;
  counter.since = now;
  write_("refused a request: " + reason + ": " + details +
         " (more of these are counted, not logged, for " +
         std::to_string(interval_us_ / 1'000'000) + " s)");
}

void RefusalLog::Flush(std::int64_t now) {
  for (auto& [reason, counter] : counters_) {
    if (!counter.open || now - counter.since < interval_us_) continue;
    if (counter.pending == 0) {
      counter.open = false;  // quiet: the next one is logged in full
      continue;
    }
    char seconds[32];
    std::snprintf(seconds, sizeof(seconds), "%.0f",
                  static_cast<double>(now - counter.since) * 1e-6);
    write_("refused " + std::to_string(counter.pending) + " more requests in the last " + seconds +
           " s: " + reason + " (" + std::to_string(counter.total) + " since the start)");
    counter.pending = 0;
    counter.since = now;
  }
}

std::uint64_t RefusalLog::total(const std::string& reason) const {
  const auto it = counters_.find(reason);
  return it == counters_.end() ? 0 : it->second.total;
}

bool RateLimit::Take(std::int64_t now) {
  if (!started_ || now - since_ >= interval_us_ || now < since_) {
    started_ = true;
    since_ = now;
    taken_ = 0;
  }
  if (taken_ >= per_interval_) return false;
  ++taken_;
  return true;
}

}  // namespace selfcal::daemon
