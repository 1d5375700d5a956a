#include "daemon/refusal_log.h"

#include <gtest/gtest.h>

#include <vector>

#include "core/util/printable.h"

namespace selfcal::daemon {
namespace {

TEST(RefusalLog, LogsTheFirstOfEachReasonThenOneCountPerInterval) {
  std::vector<std::string> lines;
  RefusalLog log(10'000'000, [&](const std::string& line) { lines.push_back(line); });
  for (int i = 0; i < 1000; ++i)
    log.Count("wrong signature", "START nonce=" + std::to_string(i), i);
  log.Count("unsigned", "ABORT nonce=x", 5);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_NE(lines[0].find("wrong signature: START nonce=0"), std::string::npos) << lines[0];
  log.Flush(9'999'999);
  EXPECT_EQ(lines.size(), 2u) << "the interval has not ended";
  log.Flush(10'000'000);
  ASSERT_EQ(lines.size(), 3u) << "one count line; nothing more of 'unsigned'";
  EXPECT_NE(lines[2].find("refused 999 more requests in the last 10 s: wrong signature"),
            std::string::npos)
      << lines[2];
  // A sustained flood: one line per interval; a quiet reason is logged in full again.
  for (int i = 0; i < 10; ++i) log.Count("wrong signature", "more", 10'000'001 + i);
  log.Flush(20'000'000);
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_NE(lines[3].find("refused 10 more"), std::string::npos) << lines[3];
  log.Flush(30'000'000);
  log.Count("wrong signature", "again", 30'000'001);
  ASSERT_EQ(lines.size(), 5u);
  EXPECT_NE(lines[4].find("wrong signature: again"), std::string::npos) << lines[4];
  EXPECT_EQ(log.total("wrong signature"), 1011u);
}

TEST(RateLimit, AllowsSoManyPerInterval) {
  RateLimit limit(3, 1'000'000);
  int taken = 0;
  for (int i = 0; i < 100; ++i) taken += limit.Take(i);
  EXPECT_EQ(taken, 3);
  EXPECT_TRUE(limit.Take(1'000'000));
}

TEST(Printable, EscapesControlCharactersAndCutsLongText) {
  EXPECT_EQ(Printable("plain text"), "plain text");
  EXPECT_EQ(Printable("a\nb\x1b[2J\\"), "a\\x0ab\\x1b[2J\\\\");
  EXPECT_EQ(Printable("\xc3\xa9"), "\\xc3\\xa9");
  EXPECT_EQ(Printable(std::string(100, 'x'), 8), "xxxxxxxx...(100 bytes)");
}

}  // namespace
}  // namespace selfcal::daemon
