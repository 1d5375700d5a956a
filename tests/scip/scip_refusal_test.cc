// Status codes as types: what a reply's status means for its command, and refusals that callers
// branch on by kind (protocols.md 1.3).
#include <gtest/gtest.h>

#include <string>

#include "protocols/scip/block.h"
#include "protocols/scip/replies.h"

namespace selfcal::scip {
namespace {

Block Reply(std::string echo, std::string status) {
  Block block;
  block.echo = std::move(echo);
  block.status = std::move(status);
  return block;
}

TEST(ScipRefusal, ClassifiesEveryKindOfStatus) {
  EXPECT_EQ(ClassifyStatus("QT", "00"), StatusKind::kDone);
  EXPECT_EQ(ClassifyStatus("BM", "02"), StatusKind::kDone);   // laser already on
  EXPECT_EQ(ClassifyStatus("TM0", "02"), StatusKind::kDone);  // already in time-adjust mode
  EXPECT_EQ(ClassifyStatus("TM2", "03"), StatusKind::kDone);
  EXPECT_EQ(ClassifyStatus("MD0000108001000", "99"), StatusKind::kScanData);
  EXPECT_EQ(ClassifyStatus("GD0000108001", "99"), StatusKind::kRefused);  // single scans: no 99
  EXPECT_EQ(ClassifyStatus("QT", "0E"), StatusKind::kTimeAdjustMode);
  EXPECT_EQ(ClassifyStatus("MD0000108001000", "04"), StatusKind::kRefused);
  EXPECT_EQ(ClassifyStatus("MD0000108001000", "10"), StatusKind::kRefused);  // laser off
  EXPECT_EQ(ClassifyStatus("TM1", "03"), StatusKind::kRefused);
  // What a booting UTM answers to TM0 and BM (urg_sim's BOOTING state): try again soon.
  EXPECT_EQ(ClassifyStatus("TM0", "10"), StatusKind::kDenied);
  EXPECT_EQ(ClassifyStatus("TM0;7", "10"), StatusKind::kDenied);
  EXPECT_EQ(ClassifyStatus("BM", "10"), StatusKind::kDenied);
  EXPECT_EQ(ClassifyStatus("GD0000108001", "10"), StatusKind::kRefused);  // laser off
  EXPECT_EQ(ClassifyStatus("MD0000108001000", "21"), StatusKind::kMeasurementStopped);
  EXPECT_EQ(ClassifyStatus("MD0000108001000", "49"), StatusKind::kMeasurementStopped);
  EXPECT_EQ(ClassifyStatus("MD0000108001000", "50"), StatusKind::kHardwareTrouble);
  EXPECT_EQ(ClassifyStatus("MD0000108001000", "97"), StatusKind::kHardwareTrouble);
  EXPECT_EQ(ClassifyStatus("VV", "0L"), StatusKind::kHardwareTrouble);
  EXPECT_EQ(ClassifyStatus("VV", ""), StatusKind::kRefused);  // a block with only an echo
  EXPECT_EQ(ClassifyStatus("VV", "?!"), StatusKind::kRefused);
}

TEST(ScipRefusal, RefusalsCarryCommandCodeAndMeaning) {
  EXPECT_FALSE(RefusalOf(Reply("VV", "00")));
  EXPECT_FALSE(RefusalOf(Reply("TM0", "02")));
  const auto time_adjust = RefusalOf(Reply("QT", "0E"));
  ASSERT_TRUE(time_adjust);
  EXPECT_EQ(time_adjust->kind, StatusKind::kTimeAdjustMode);
  EXPECT_EQ(time_adjust->command, "QT");
  EXPECT_EQ(time_adjust->status, "0E");
  const auto range = RefusalOf(Reply("MD0000108001000", "04"));
  ASSERT_TRUE(range);
  EXPECT_EQ(range->kind, StatusKind::kRefused);
  EXPECT_EQ(range->Meaning(), "end step out of range");
  EXPECT_EQ(range->Describe(), "MD0000108001000 answered 04 (end step out of range)");
  // Scan data is not an acknowledgement: a scan command's first reply must be 00.
  const auto data = RefusalOf(Reply("MD0000108001000", "99"));
  ASSERT_TRUE(data);
  EXPECT_EQ(data->kind, StatusKind::kScanData);
}

TEST(ScipRefusal, OnlyABaudChangeAnsweredZeroZeroMovesTheLink) {
  EXPECT_EQ(ClassifyBaudChange("00"), BaudChange::kSwitched);
  EXPECT_EQ(ClassifyBaudChange("03"), BaudChange::kUnchanged);  // already at that rate
  EXPECT_EQ(ClassifyBaudChange("04"), BaudChange::kUnchanged);  // not supported by this sensor
  EXPECT_EQ(ClassifyBaudChange("0F"), BaudChange::kUnchanged);
  EXPECT_EQ(ClassifyBaudChange("01"), BaudChange::kRefused);
  EXPECT_EQ(ClassifyBaudChange("02"), BaudChange::kRefused);
  EXPECT_EQ(ClassifyBaudChange("0E"), BaudChange::kRefused);
  EXPECT_EQ(ClassifyBaudChange(""), BaudChange::kRefused);  // no reply
}

}  // namespace
}  // namespace selfcal::scip
