#include <gtest/gtest.h>

#include <vector>

#include "core/util/printable.h"
#include "daemon/request_policy.h"

namespace selfcal::daemon {
namespace {

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
