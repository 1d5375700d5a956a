// CANopen (CiA 301) frames: the predefined connection set, golden values, and bad frames that
// are errors saying where.
#include "protocols/canopen/canopen_frames.h"

#include <gtest/gtest.h>

#include <string>

namespace selfcal::canopen {
namespace {

CanFrame Frame(const std::string& text) {
  auto frame = ParseCansend(text);
  EXPECT_TRUE(frame.ok()) << text << ": " << (frame.ok() ? "" : frame.error().message);
  return frame.ok() ? *frame : CanFrame{};
}

TEST(CanopenFrames, ClassifiesThePredefinedConnectionSet) {
  EXPECT_EQ(Classify(Frame("000#0101")).kind, FrameKind::kNmt);
  EXPECT_EQ(Classify(Frame("080#")).kind, FrameKind::kSync);
  const Classified emcy = Classify(Frame("083#1023000000000000"));
  EXPECT_EQ(emcy.kind, FrameKind::kEmergency);
  EXPECT_EQ(emcy.node, 3);
  const Classified tpdo = Classify(Frame("2A5#00"));
  EXPECT_EQ(tpdo.kind, FrameKind::kTpdo);
  EXPECT_EQ(tpdo.node, 0x25);
  EXPECT_EQ(tpdo.pdo, 2);
  EXPECT_EQ(Classify(Frame("705#7F")).kind, FrameKind::kHeartbeat);
  EXPECT_EQ(Classify(Frame("585#4B41600037060000")).kind, FrameKind::kSdoResponse);
  EXPECT_EQ(Classify(Frame("605#4041600000000000")).kind, FrameKind::kSdoRequest);
}

TEST(CanopenFrames, GoldenValues) {
  // TPDO1 of node 1: statusword 0x0637, position actual value 0x00012345 = 74565 counts.
  const CanFrame tpdo = Frame("181#370645230100");
  EXPECT_EQ(ReadInt32(tpdo, 2).value(), 74565);
  // Negative counts: 0xFFFFF000 = -4096.
  EXPECT_EQ(ReadInt32(Frame("181#370600F0FFFF"), 2).value(), -4096);
  EXPECT_EQ(DecodeHeartbeat(Frame("701#00")).value(), NmtState::kBootUp);
  EXPECT_EQ(DecodeHeartbeat(Frame("701#05")).value(), NmtState::kOperational);
  EXPECT_EQ(DecodeHeartbeat(Frame("701#85")).value(), NmtState::kOperational);  // toggle bit
  EXPECT_EQ(DecodeHeartbeat(Frame("701#7F")).value(), NmtState::kPreOperational);
  EXPECT_EQ(DecodeSyncCounter(Frame("080#")).value(), 0);
  EXPECT_EQ(DecodeSyncCounter(Frame("080#07")).value(), 7);
  EXPECT_EQ(FormatCansend(MakeNmt(NmtCommand::kStart, 5)), "000#0105");
  EXPECT_EQ(FormatCansend(MakeNmt(NmtCommand::kResetNode, 0)), "000#8100");
  EXPECT_EQ(FormatCansend(MakeSync()), "080#");
  EXPECT_EQ(FormatCansend(MakeSync(12)), "080#0C");
}

TEST(CanopenFrames, BadFramesAreErrorsThatSayWhere) {
  auto short_pdo = ReadInt32(Frame("181#3706452301"), 2);
  ASSERT_FALSE(short_pdo.ok());
  EXPECT_NE(short_pdo.error().message.find("0x181"), std::string::npos)
      << short_pdo.error().message;
  EXPECT_NE(short_pdo.error().message.find("byte 2"), std::string::npos);
  auto state = DecodeHeartbeat(Frame("703#42"));
  ASSERT_FALSE(state.ok());
  EXPECT_NE(state.error().message.find("node 3"), std::string::npos) << state.error().message;
  EXPECT_FALSE(DecodeHeartbeat(Frame("703#0505")).ok());
  EXPECT_FALSE(DecodeSyncCounter(Frame("080#0102")).ok());
  EXPECT_FALSE(ParseCansend("1234#00").ok());
  EXPECT_FALSE(ParseCansend("12G#00").ok());
  EXPECT_FALSE(ParseCansend("123#0").ok());
  EXPECT_FALSE(ParseCansend("123#001122334455667788").ok());
}

TEST(CanopenFrames, OversizedFramesAreErrorsNotReadsPastTheFrame) {
  CanFrame oversized = Frame("181#3706452301000000");
  oversized.length = 12;  // a corrupted length from a socket: never read beyond data[7]
  auto value = ReadInt32(oversized, 6);
  ASSERT_FALSE(value.ok());
  EXPECT_NE(value.error().message.find("0x181: length 12"), std::string::npos)
      << value.error().message;
  EXPECT_FALSE(DecodeHeartbeat(oversized).ok());
  EXPECT_FALSE(DecodeSyncCounter(oversized).ok());
  EXPECT_EQ(FormatCansend(oversized), "181#3706452301000000");  // at most the 8 bytes it holds
  // Truncated and corrupted cansend text: the error names the character.
  auto corrupted = ParseCansend("181#37Z6");
  ASSERT_FALSE(corrupted.ok());
  EXPECT_NE(corrupted.error().message.find("character 6"), std::string::npos)
      << corrupted.error().message;
  EXPECT_FALSE(ParseCansend("").ok());
  EXPECT_FALSE(ParseCansend("#00").ok());
  EXPECT_FALSE(ParseCansend("181").ok());
  EXPECT_FALSE(ParseCansend("800#00").ok());  // beyond 11 bits
}

}  // namespace
}  // namespace selfcal::canopen
