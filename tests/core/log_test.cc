// RateLimitedLog on explicit times: a burst passes, the rest is counted and summed up once the
// window is over, kinds are limited apart, and nothing suppressed is ever silently lost.
#include "core/util/log.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace selfcal {
namespace {

using Clock = RateLimitedLog::Clock;
using std::chrono::milliseconds;

struct Collected {
  std::vector<std::string> lines;
  LogSink Sink() {
    return [this](LogLevel, const std::string& text) { lines.push_back(text); };
  }
};

TEST(RateLimitedLog, PassesABurstThenSumsUpTheRest) {
  Collected out;
  RateLimitedLog log(out.Sink(), 3, std::chrono::seconds(10));
  const Clock::time_point t0{};
  for (int i = 0; i < 847; ++i) {
    log.Log(LogLevel::kWarning, "rejected block", "byte " + std::to_string(i) + ": junk",
            t0 + milliseconds(i));
  }
  ASSERT_EQ(out.lines.size(), 3u);
  EXPECT_EQ(out.lines[0], "byte 0: junk");
  EXPECT_EQ(out.lines[2], "byte 2: junk");
  log.Flush(t0 + milliseconds(9999));
  EXPECT_EQ(out.lines.size(), 3u) << "the window is not over yet";
  log.Flush(t0 + milliseconds(10000));
  ASSERT_EQ(out.lines.size(), 4u);
  EXPECT_EQ(out.lines[3],
            "rejected block: 844 more suppressed in the last 10.0 s; last: byte 846: junk");
  // A new window passes a new burst.
  log.Log(LogLevel::kWarning, "rejected block", "again", t0 + milliseconds(10001));
  ASSERT_EQ(out.lines.size(), 5u);
  EXPECT_EQ(out.lines[4], "again");
}

TEST(RateLimitedLog, TheNextMessageAfterTheWindowCarriesTheCount) {
  Collected out;
  RateLimitedLog log(out.Sink(), 1, std::chrono::seconds(1));
  const Clock::time_point t0{};
  log.Log(LogLevel::kWarning, "k", "a", t0);
  log.Log(LogLevel::kWarning, "k", "b", t0 + milliseconds(10));
  log.Log(LogLevel::kWarning, "k", "c", t0 + milliseconds(20));
  log.Log(LogLevel::kWarning, "k", "d", t0 + milliseconds(1500));
  ASSERT_EQ(out.lines.size(), 3u);
  EXPECT_EQ(out.lines[0], "a");
  EXPECT_EQ(out.lines[1], "k: 2 more suppressed in the last 1.5 s; last: c");
  EXPECT_EQ(out.lines[2], "d");
}

TEST(RateLimitedLog, KindsAreLimitedApartAndFlushAllReportsEverything) {
  Collected out;
  RateLimitedLog log(out.Sink(), 2, std::chrono::seconds(10));
  const Clock::time_point t0{};
  for (int i = 0; i < 5; ++i) {
    log.Log(LogLevel::kWarning, "one", "one " + std::to_string(i), t0);
    log.Log(LogLevel::kWarning, "two", "two " + std::to_string(i), t0);
  }
  EXPECT_EQ(out.lines.size(), 4u);
  log.FlushAll();
  ASSERT_EQ(out.lines.size(), 6u);
  EXPECT_NE(out.lines[4].find("one: 3 more suppressed"), std::string::npos) << out.lines[4];
  EXPECT_NE(out.lines[5].find("two: 3 more suppressed"), std::string::npos) << out.lines[5];
  log.FlushAll();
  EXPECT_EQ(out.lines.size(), 6u) << "each suppressed message is reported once";
}

}  // namespace
}  // namespace selfcal
