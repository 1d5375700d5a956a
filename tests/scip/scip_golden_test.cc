// Golden tests: the captured and spec exchanges of ../shared/protocols.md section 1, bytes in,
// values out (and values in, bytes out for the encoders).
#include <gtest/gtest.h>

#include <string>

#include "protocols/scip/block.h"
#include "protocols/scip/commands.h"
#include "protocols/scip/encoding.h"
#include "protocols/scip/replies.h"

namespace selfcal::scip {
namespace {

// protocols.md 1.7: real capture, URG-04LX-UG01 over serial.
constexpr std::string_view kVvCapture =
    "VV\n00P\nVEND:Hokuyo Automatic Co.,Ltd.;[\nPROD:SOKUIKI Sensor "
    "URG-04LX-UG01(Simple-URG);[\nFIRM:3.4.03(17/Dec./2012);T\nPROT:SCIP 2.0;N\n"
    "SERI:H1510998;V\n\n";
constexpr std::string_view kBmCapture = "BM\n02R\n\n";
// protocols.md 1.6: UTM-30LX-EW PP reply.
constexpr std::string_view kPpUtm =
    "PP\n00P\nMODL:UTM-30LX-EW;I\nDMIN:23;7\nDMAX:60000;J\nARES:1440;^\nAMIN:0;?\n"
    "AMAX:1080;Z\nAFRT:540;0\nSCAN:2400;U\n\n";
constexpr std::string_view kGd = "GD0540054401\n00P\n0N90W\n0?X0?Y0GL00G>YPP\n\n";
constexpr std::string_view kTm1 = "TM1\n00P\nm2@0?\n\n";
constexpr std::string_view kMeAck = "ME0000108001000\n00P\n\n";

Block Parse(std::string_view bytes) {
  auto block = ParseBlock(bytes);
  EXPECT_TRUE(block.ok()) << (block.ok() ? "" : block.error().message);
  return block.ok() ? *block : Block{};
}

TEST(ScipEncoding, SpecExamples) {
  EXPECT_EQ(Checksum("Hokuyo"), 'o');
  EXPECT_EQ(DecodeValue("CB"), 1234u);
  EXPECT_EQ(DecodeValue("1Dh"), 5432u);
  EXPECT_EQ(DecodeValue("m2@0"), 16000000u);
  EXPECT_EQ(EncodeValue(1234, 2), "CB");
  EXPECT_EQ(EncodeValue(5432, 3), "1Dh");
  EXPECT_EQ(EncodeValue(16000000, 4), "m2@0");
  EXPECT_FALSE(DecodeValue("1p").has_value());  // 'p' = 0x70 is outside the alphabet
  EXPECT_FALSE(DecodeValue("/0").has_value());
  EXPECT_FALSE(DecodeValue("").has_value());
  EXPECT_FALSE(DecodeValue("00000").has_value());
  EXPECT_EQ(MaxEncodedValue(2), 4095u);
  EXPECT_EQ(MaxEncodedValue(3), 262143u);
  EXPECT_EQ(MaxEncodedValue(4), 16777215u);
  EXPECT_EQ(EncodeValue(300000, 3), "ooo");  // clamped, never outside the alphabet
}

TEST(ScipEncoding, StatusChecksumsFromProtocolsMd) {
  for (const auto& [status, line] :
       std::vector<std::pair<std::string, std::string>>{{"00", "00P\n"},
                                                        {"99", "99b\n"},
                                                        {"01", "01Q\n"},
                                                        {"02", "02R\n"},
                                                        {"03", "03S\n"},
                                                        {"04", "04T\n"},
                                                        {"0E", "0Ee\n"},
                                                        {"0L", "0Ll\n"},
                                                        {"10", "10Q\n"},
                                                        {"0C", "0Cc\n"},
                                                        {"0D", "0Dd\n"},
                                                        {"0F", "0Ff\n"}}) {
    std::string out;
    AppendStatusLine(out, status);
    EXPECT_EQ(out, line) << status;
  }
}

TEST(ScipCommands, EncodesEveryCommand) {
  EXPECT_EQ(*EncodeSimple(SimpleCommand::kVV), "VV\n");
  EXPECT_EQ(*EncodeSimple(SimpleCommand::kPP), "PP\n");
  EXPECT_EQ(*EncodeSimple(SimpleCommand::kII), "II\n");
  EXPECT_EQ(*EncodeSimple(SimpleCommand::kBM), "BM\n");
  EXPECT_EQ(*EncodeSimple(SimpleCommand::kQT), "QT\n");
  EXPECT_EQ(*EncodeSimple(SimpleCommand::kRS), "RS\n");
  EXPECT_EQ(*EncodeSimple(SimpleCommand::kTM0), "TM0\n");
  EXPECT_EQ(*EncodeSimple(SimpleCommand::kTM1), "TM1\n");
  EXPECT_EQ(*EncodeSimple(SimpleCommand::kTM2), "TM2\n");
  EXPECT_EQ(*EncodeSimple(SimpleCommand::kVV, "abc"), "VV;abc\n");
  EXPECT_FALSE(EncodeSimple(SimpleCommand::kVV, "12345678901234567").ok());
  EXPECT_FALSE(EncodeSimple(SimpleCommand::kVV, "a b").ok());

  EXPECT_EQ(*EncodeScanRequest({ScanType::kGD, 540, 544, 1}), "GD0540054401\n");
  EXPECT_EQ(*EncodeScanRequest({ScanType::kGS, 0, 1080, 2}), "GS0000108002\n");
  EXPECT_EQ(*EncodeScanRequest({ScanType::kGE, 0, 10, 0}), "GE0000001000\n");
  EXPECT_EQ(*EncodeScanRequest({ScanType::kHD, 0, 10, 1}), "HD0000001001\n");
  EXPECT_EQ(*EncodeScanRequest({ScanType::kME, 0, 1080, 1, 0, 0}), "ME0000108001000\n");
  EXPECT_EQ(*EncodeScanRequest({ScanType::kMD, 0, 29, 1, 0, 2}), "MD0000002901002\n");
  EXPECT_EQ(*EncodeScanRequest({ScanType::kMS, 100, 200, 3, 9, 99}), "MS0100020003999\n");
  EXPECT_EQ(*EncodeScanRequest({ScanType::kND, 0, 1080, 1, 1, 5}), "ND0000108001105\n");
  EXPECT_EQ(*EncodeScanRequest({ScanType::kMD, 0, 1080, 1, 0, 0}, "t1"), "MD0000108001000;t1\n");
  EXPECT_FALSE(EncodeScanRequest({ScanType::kMD, 10, 9}).ok());
  EXPECT_FALSE(EncodeScanRequest({ScanType::kMD, 0, 10000}).ok());
  EXPECT_FALSE(EncodeScanRequest({ScanType::kMD, 0, 10, 100}).ok());
  EXPECT_FALSE(EncodeScanRequest({ScanType::kMD, 0, 10, 1, 10}).ok());
  EXPECT_FALSE(EncodeScanRequest({ScanType::kMD, 0, 10, 1, 0, 100}).ok());
  EXPECT_EQ(*EncodeBaudChange(115200), "SS115200\n");
  EXPECT_EQ(*EncodeBaudChange(19200), "SS019200\n");
  EXPECT_FALSE(EncodeBaudChange(1000000).ok());
}

TEST(ScipCommands, NumberedCommandsMatchTheirOwnReplies) {
  EXPECT_EQ(EncodeNumbered(SimpleCommand::kTM1, 0), "TM1;0\n");
  EXPECT_EQ(EncodeNumbered(SimpleCommand::kTM1, 18446744073709551615u),
            "TM1;18446744073709551615\n");
  EXPECT_EQ(SequenceOf("TM1;42", SimpleCommand::kTM1), 42u);
  EXPECT_EQ(SequenceOf(EchoOf(EncodeNumbered(SimpleCommand::kTM1, 7)), SimpleCommand::kTM1), 7u);
  EXPECT_FALSE(SequenceOf("TM1", SimpleCommand::kTM1));
  EXPECT_FALSE(SequenceOf("TM1;", SimpleCommand::kTM1));
  EXPECT_FALSE(SequenceOf("TM1;4x", SimpleCommand::kTM1));
  EXPECT_FALSE(SequenceOf("TM1;-4", SimpleCommand::kTM1));
  EXPECT_FALSE(SequenceOf("TM1;99999999999999999999", SimpleCommand::kTM1));  // overflows
  EXPECT_FALSE(SequenceOf("TM0;4", SimpleCommand::kTM1));
  EXPECT_FALSE(SequenceOf("TM12;4", SimpleCommand::kTM1));
  EXPECT_EQ(EchoOf("MD0000108001000;t1\n"), "MD0000108001000;t1");
  EXPECT_EQ(EchoOf("QT"), "QT");
}

TEST(ScipCommands, ScanEchoesMatchTheirRequestWhileCountingDown) {
  const ScanRequest md{ScanType::kMD, 0, 1080, 1, 0, 0};
  EXPECT_TRUE(IsEchoOf("MD0000108001000", md));
  EXPECT_TRUE(IsEchoOf("MD0000108001099", md));  // the count counts down
  EXPECT_TRUE(IsEchoOf("MD0000108001000;t1", md));
  EXPECT_FALSE(IsEchoOf("MD0000108001100", md));  // another skip
  EXPECT_FALSE(IsEchoOf("MD0000108002000", md));  // another cluster
  EXPECT_FALSE(IsEchoOf("ME0000108001000", md));
  EXPECT_FALSE(IsEchoOf("MD00001080", md));
  EXPECT_FALSE(IsEchoOf("TM1;3", md));
  const ScanRequest gd{ScanType::kGD, 540, 544, 1};
  EXPECT_TRUE(IsEchoOf("GD0540054401", gd));
  EXPECT_FALSE(IsEchoOf("GD0540054501", gd));
  EXPECT_FALSE(IsEchoOf("GD0540054401", {ScanType::kGD, 0, 10000}));  // unencodable request
}

TEST(ScipGolden, VersionCaptureOfUrg04lx) {
  const Block block = Parse(kVvCapture);
  EXPECT_EQ(block.echo, "VV");
  EXPECT_EQ(block.status, "00");
  ASSERT_EQ(block.lines.size(), 5u);
  const auto version = DecodeVersion(block);
  ASSERT_TRUE(version.ok()) << version.error().message;
  EXPECT_EQ(version->vendor, "Hokuyo Automatic Co.,Ltd.");
  EXPECT_EQ(version->product, "SOKUIKI Sensor URG-04LX-UG01(Simple-URG)");
  EXPECT_EQ(version->firmware, "3.4.03(17/Dec./2012)");
  EXPECT_EQ(version->protocol, "SCIP 2.0");
  EXPECT_EQ(version->serial, "H1510998");
}

TEST(ScipGolden, LaserAlreadyOnIsSuccess) {
  const Block block = Parse(kBmCapture);
  EXPECT_EQ(block.status, "02");
  EXPECT_TRUE(IsSuccess(block.echo, block.status));
  EXPECT_EQ(StatusMeaning(block.echo, block.status), "laser already on");
  EXPECT_FALSE(IsSuccess("BM", "01"));
}

TEST(ScipGolden, Utm30lxParameters) {
  const auto parameters = DecodeParameters(Parse(kPpUtm));
  ASSERT_TRUE(parameters.ok()) << parameters.error().message;
  EXPECT_EQ(parameters->model, "UTM-30LX-EW");
  EXPECT_EQ(parameters->min_range_mm, 23);
  EXPECT_EQ(parameters->max_range_mm, 60000);
  EXPECT_EQ(parameters->steps_per_rotation, 1440);
  EXPECT_EQ(parameters->first_step, 0);
  EXPECT_EQ(parameters->last_step, 1080);
  EXPECT_EQ(parameters->front_step, 540);
  EXPECT_EQ(parameters->rotation_rpm, 2400);
}

TEST(ScipGolden, InfoLinesAreEncodedAsCaptured) {
  std::string out = "PP\n";
  AppendStatusLine(out, "00");
  AppendInfoLine(out, "MODL", "UTM-30LX-EW");
  AppendInfoLine(out, "DMIN", "23");
  AppendInfoLine(out, "DMAX", "60000");
  AppendInfoLine(out, "ARES", "1440");
  AppendInfoLine(out, "AMIN", "0");
  AppendInfoLine(out, "AMAX", "1080");
  AppendInfoLine(out, "AFRT", "540");
  AppendInfoLine(out, "SCAN", "2400");
  out.push_back('\n');
  EXPECT_EQ(out, kPpUtm);
}

TEST(ScipGolden, SingleScanGd) {
  const Block block = Parse(kGd);
  const auto echo = ParseScanEcho(block.echo);
  ASSERT_TRUE(echo.ok()) << echo.error().message;
  EXPECT_EQ(echo->request.type, ScanType::kGD);
  EXPECT_EQ(echo->request.start_step, 540);
  EXPECT_EQ(echo->request.end_step, 544);
  EXPECT_EQ(echo->request.cluster, 1);
  ScanData scan;
  const auto status = DecodeScan(block, *echo, scan);
  ASSERT_TRUE(status.ok()) << status.error().message;
  EXPECT_EQ(scan.timestamp_ms, 123456u);
  EXPECT_EQ(scan.ranges_mm, (std::vector<std::uint32_t>{1000, 1001, 1500, 23, 60000}));
  EXPECT_TRUE(scan.intensities.empty());

  std::string encoded = "GD0540054401\n";
  AppendStatusLine(encoded, "00");
  AppendScanData(encoded, ScanType::kGD, {123456, {1000, 1001, 1500, 23, 60000}, {}, {}, {}});
  encoded.push_back('\n');
  EXPECT_EQ(encoded, kGd);
}

TEST(ScipGolden, TimeRead) {
  const auto time = DecodeTime(Parse(kTm1));
  ASSERT_TRUE(time.ok()) << time.error().message;
  EXPECT_EQ(*time, 16000000u);
}

TEST(ScipGolden, MeAcknowledgeHasNoData) {
  const Block block = Parse(kMeAck);
  EXPECT_EQ(block.status, "00");
  EXPECT_TRUE(block.lines.empty());
  const auto echo = ParseScanEcho(block.echo);
  ASSERT_TRUE(echo.ok());
  EXPECT_EQ(echo->request.type, ScanType::kME);
  EXPECT_EQ(echo->request.end_step, 1080);
  EXPECT_EQ(echo->request.count, 0);
}

// protocols.md 1.7: MD with 30 steps (90 characters -> 64 + 26), 2 scans requested; each scan's
// echo carries the remaining count, the 3-character values straddle the line break.
TEST(ScipGolden, StreamedScansStraddleLinesAndCountDown) {
  std::vector<std::uint32_t> ranges;
  for (std::uint32_t i = 0; i < 30; ++i) ranges.push_back(1000 + 37 * i);
  std::string stream = "MD0000002901002\n00P\n\n";
  for (const char* echo : {"MD0000002901001", "MD0000002901000"}) {
    stream += echo;
    stream += "\n99b\n";
    AppendScanData(stream, ScanType::kMD, {5000, ranges, {}, {}, {}});
    stream += "\n";
  }
  // The timestamp line of the capture: "01>8" + 'G'.
  EXPECT_EQ(DecodeValue("01>8"), 5000u);
  EXPECT_NE(stream.find("MD0000002901001\n99b\n01>8G\n"), std::string::npos);

  BlockFramer framer;
  // Feed in awkward chunks: 7 bytes at a time.
  for (std::size_t i = 0; i < stream.size(); i += 7) framer.Append(stream.substr(i, 7));
  auto ack = framer.Next();
  ASSERT_TRUE(ack.has_value() && ack->ok());
  EXPECT_EQ((*ack)->status, "00");
  for (int remaining : {1, 0}) {
    auto block = framer.Next();
    ASSERT_TRUE(block.has_value() && block->ok()) << (block ? block->error().message : "none");
    ASSERT_EQ((*block)->lines.size(), 3u);
    EXPECT_EQ((*block)->lines[1].size(), 64u);
    EXPECT_EQ((*block)->lines[2].size(), 26u);
    const auto echo = ParseScanEcho((*block)->echo);
    ASSERT_TRUE(echo.ok());
    EXPECT_EQ(echo->request.count, remaining);
    ScanData scan;
    ASSERT_TRUE(DecodeScan(**block, *echo, scan).ok());
    EXPECT_EQ(scan.ranges_mm, ranges);
    EXPECT_EQ(scan.timestamp_ms, 5000u);
  }
  EXPECT_FALSE(framer.Next().has_value());
}

TEST(ScipGolden, UrgStampedQtAndJunkBlocks) {
  BlockFramer framer;
  framer.Append("FOO\nBAR\nQT\n\nQT\n\nQT\n00P\n\n");
  auto junk = framer.Next();
  ASSERT_TRUE(junk.has_value());
  ASSERT_FALSE(junk->ok());  // "BAR" is no status line: its third byte (offset 6) is no sum
  EXPECT_NE(junk->error().message.find("byte 6"), std::string::npos) << junk->error().message;
  auto no_status = framer.Next();
  ASSERT_TRUE(no_status.has_value());
  ASSERT_FALSE(no_status->ok());
  EXPECT_NE(no_status->error().message.find("no status line"), std::string::npos);
  auto qt = framer.Next();
  ASSERT_TRUE(qt.has_value() && qt->ok());
  EXPECT_EQ((*qt)->echo, "QT");
  EXPECT_EQ((*qt)->status, "00");
}

TEST(ScipReplies, IntensityAndMultiEcho) {
  for (const ScanType type : {ScanType::kME, ScanType::kGE}) {
    std::string bytes = type == ScanType::kME ? "ME0010001901000\n99b\n" : "GE0010001901\n00P\n";
    ScanValues values;
    values.timestamp_ms = 42;
    for (std::uint32_t i = 0; i < 10; ++i) {
      values.ranges_mm.push_back(500 + i);
      values.intensities.push_back(7000 + 3 * i);
    }
    AppendScanData(bytes, type, values);
    bytes += "\n";
    const Block block = Parse(bytes);
    ScanData scan;
    const auto echo = ParseScanEcho(block.echo);
    ASSERT_TRUE(echo.ok());
    ASSERT_TRUE(DecodeScan(block, *echo, scan).ok());
    EXPECT_EQ(scan.ranges_mm, values.ranges_mm);
    EXPECT_EQ(scan.intensities, values.intensities);
  }
  // ND: value 1 has three echoes, value 3 two.
  ScanValues values;
  values.timestamp_ms = 99;
  values.ranges_mm = {100, 200, 300, 400};
  values.extra_ranges = {{}, {210, 220}, {}, {410}};
  std::string bytes = "ND0000000301000\n99b\n";
  AppendScanData(bytes, ScanType::kND, values);
  bytes += "\n";
  const Block block = Parse(bytes);
  ScanData scan;
  ASSERT_TRUE(DecodeScan(block, *ParseScanEcho(block.echo), scan).ok());
  EXPECT_EQ(scan.ranges_mm, values.ranges_mm);
  EXPECT_EQ(scan.echo_ranges_mm, (std::vector<std::uint32_t>{100, 200, 210, 220, 300, 400, 410}));
  EXPECT_EQ(scan.echo_begin, (std::vector<std::uint32_t>{0, 1, 4, 5, 7}));
}

TEST(ScipReplies, StatusMeanings) {
  EXPECT_EQ(StatusMeaning("MD0000108001000", "04"), "end step out of range");
  EXPECT_EQ(StatusMeaning("GD0000108001", "10"), "laser off");
  EXPECT_EQ(StatusMeaning("TM2", "03"), "time-adjust mode already off");
  EXPECT_EQ(StatusMeaning("XX", "0E").substr(0, 17), "undefined command");
  EXPECT_EQ(StatusMeaning("MD0000108001000", "55"), "hardware trouble");
  EXPECT_TRUE(IsSuccess("TM0", "02"));
  EXPECT_TRUE(IsSuccess("TM2", "03"));
  EXPECT_FALSE(IsSuccess("TM1", "03"));
  EXPECT_TRUE(IsSuccess("MD0000108001000", "99"));
  EXPECT_FALSE(IsSuccess("GD0000108001", "99"));
  EXPECT_TRUE(IsSuccess("SS115200", "0F"));
}

}  // namespace
}  // namespace selfcal::scip
