// Commands as a sensor reads them: every encoder's output parses back to what was encoded (the
// inverse check), and every malformed line gets the status a sensor answers, in urg_sim's order.
#include <gtest/gtest.h>

#include <string>

#include "protocols/scip/block.h"
#include "protocols/scip/command_parser.h"

namespace selfcal::scip {
namespace {

// The status `line` is refused with by the framing, or "" when it frames.
std::string FramingStatus(std::string_view line) {
  const auto parsed = ParseCommandLine(line);
  const auto* refusal = std::get_if<Refusal>(&parsed);
  return refusal ? refusal->status : "";
}

// The status a scan command is refused with (framing, then parameters), or "" when accepted.
std::string ScanStatus(std::string_view line, StepRange steps = {0, 1080}) {
  const auto parsed = ParseCommandLine(line);
  if (const auto* refusal = std::get_if<Refusal>(&parsed)) return refusal->status;
  const auto scan = ParseScanCommand(std::get<CommandLine>(parsed), steps);
  const auto* refusal = std::get_if<Refusal>(&scan);
  return refusal ? refusal->status : "";
}

TEST(ScipCommandParser, EncodedScanRequestsParseBack) {
  for (const ScanType type :
       {ScanType::kGD, ScanType::kGS, ScanType::kGE, ScanType::kHD, ScanType::kHE, ScanType::kMD,
        ScanType::kMS, ScanType::kME, ScanType::kND, ScanType::kNE}) {
    ScanRequest request;
    request.type = type;
    request.start_step = 44;
    request.end_step = 725;
    request.cluster = 3;
    if (Info(type).streaming) {
      request.skip = 2;
      request.count = 17;
    }
    const std::string bytes = EncodeScanRequest(request, "t9").value();
    const auto line = ParseCommandLine(EchoOf(bytes));
    ASSERT_TRUE(std::holds_alternative<CommandLine>(line)) << bytes;
    const CommandLine& command = std::get<CommandLine>(line);
    EXPECT_EQ(command.name, CommandName::kScan);
    EXPECT_EQ(command.scan_type, type);
    EXPECT_EQ(command.tag, "t9");
    const auto scan = ParseScanCommand(command);
    ASSERT_TRUE(std::holds_alternative<ScanEcho>(scan)) << bytes;
    const ScanEcho& echo = std::get<ScanEcho>(scan);
    EXPECT_EQ(echo.request.start_step, 44);
    EXPECT_EQ(echo.request.end_step, 725);
    EXPECT_EQ(echo.request.cluster, 3);
    EXPECT_EQ(echo.request.skip, Info(type).streaming ? 2 : 0);
    EXPECT_EQ(echo.request.count, Info(type).streaming ? 17 : 0);
    EXPECT_EQ(echo.tag, "t9");
  }
}

TEST(ScipCommandParser, EncodedSimpleCommandsParseBack) {
  const std::pair<SimpleCommand, CommandName> simple[] = {
      {SimpleCommand::kVV, CommandName::kVV}, {SimpleCommand::kPP, CommandName::kPP},
      {SimpleCommand::kII, CommandName::kII}, {SimpleCommand::kBM, CommandName::kBM},
      {SimpleCommand::kQT, CommandName::kQT}, {SimpleCommand::kRS, CommandName::kRS}};
  for (const auto& [command, name] : simple) {
    const std::string bytes = EncodeSimple(command, "abc").value();
    const auto line = ParseCommandLine(EchoOf(bytes));
    ASSERT_TRUE(std::holds_alternative<CommandLine>(line)) << bytes;
    EXPECT_EQ(std::get<CommandLine>(line).name, name);
    EXPECT_EQ(std::get<CommandLine>(line).tag, "abc");
  }
  for (const SimpleCommand tm : {SimpleCommand::kTM0, SimpleCommand::kTM1, SimpleCommand::kTM2}) {
    const std::string bytes = EncodeNumbered(tm, 42);
    const auto line = ParseCommandLine(EchoOf(bytes));
    ASSERT_TRUE(std::holds_alternative<CommandLine>(line)) << bytes;
    EXPECT_EQ(std::get<CommandLine>(line).name, CommandName::kTM);
    const auto code = ParseTimeCommand(std::get<CommandLine>(line));
    ASSERT_TRUE(std::holds_alternative<SimpleCommand>(code));
    EXPECT_EQ(std::get<SimpleCommand>(code), tm);
    EXPECT_EQ(SequenceOf(std::get<CommandLine>(line).text, tm), 42u);
  }
  const std::string ss = EncodeBaudChange(115200).value();
  const auto line = ParseCommandLine(EchoOf(ss));
  ASSERT_TRUE(std::holds_alternative<CommandLine>(line));
  EXPECT_EQ(std::get<CommandLine>(line).name, CommandName::kSS);
  const auto baud = ParseBaudChange(std::get<CommandLine>(line));
  ASSERT_TRUE(std::holds_alternative<int>(baud));
  EXPECT_EQ(std::get<int>(baud), 115200);
}

TEST(ScipCommandParser, FramingRefusals) {
  EXPECT_EQ(FramingStatus("VV"), "");
  EXPECT_EQ(FramingStatus("RB"), "");
  EXPECT_EQ(FramingStatus("RT;x"), "");
  EXPECT_EQ(FramingStatus("XY"), "0E");
  EXPECT_EQ(FramingStatus("X"), "0E");
  EXPECT_EQ(FramingStatus(""), "0E");
  EXPECT_EQ(FramingStatus("TM"), "0C");
  EXPECT_EQ(FramingStatus("SS11520"), "0C");
  EXPECT_EQ(FramingStatus("MD00001080"), "0C");
  EXPECT_EQ(FramingStatus("VVx"), "0D");
  EXPECT_EQ(FramingStatus("VV;1234567890123456"), "");  // a tag of kMaxTagLength
  EXPECT_EQ(FramingStatus("VV;12345678901234567"), "0D");
  EXPECT_EQ(FramingStatus("GD00001080010"), "0D");  // a 13th character that is not ';'
  const auto refused = ParseCommandLine("VVx");
  EXPECT_EQ(std::get<Refusal>(refused).command, "VVx");
  EXPECT_EQ(std::get<Refusal>(refused).kind, StatusKind::kRefused);
  EXPECT_EQ(std::get<Refusal>(ParseCommandLine("XY")).kind, StatusKind::kTimeAdjustMode);
}

TEST(ScipCommandParser, ParameterRefusalsInTheSensorsOrder) {
  EXPECT_EQ(ScanStatus("MD0000108001000"), "");
  EXPECT_EQ(ScanStatus("MDx000108001000"), "01");
  EXPECT_EQ(ScanStatus("MD0000x08001000"), "02");
  EXPECT_EQ(ScanStatus("MD00001080x1000"), "03");
  EXPECT_EQ(ScanStatus("MD0000200001000"), "04");              // beyond AMAX
  EXPECT_EQ(ScanStatus("MD0000108001000", {10, 1080}), "04");  // before AMIN
  EXPECT_EQ(ScanStatus("MD0100005001000"), "05");
  EXPECT_EQ(ScanStatus("MD0000108001x00"), "06");
  EXPECT_EQ(ScanStatus("MD000010800100x"), "07");
  // Earlier checks win: a bad start step before a bad skip, the range before the order.
  EXPECT_EQ(ScanStatus("MDx00010800100x"), "01");
  EXPECT_EQ(ScanStatus("MD9999200001000"), "04");
  EXPECT_EQ(ScanStatus("GD0000108001"), "");  // single scans carry no skip or count
  const auto tm = ParseTimeCommand(std::get<CommandLine>(ParseCommandLine("TM3")));
  EXPECT_EQ(std::get<Refusal>(tm).status, "01");
  const auto ss = ParseBaudChange(std::get<CommandLine>(ParseCommandLine("SS11520x")));
  EXPECT_EQ(std::get<Refusal>(ss).status, "01");
}

TEST(ScipCommandParser, TimeAdjustModeAllowsOnlyTimeAndReset) {
  EXPECT_TRUE(AllowedInTimeAdjustMode(CommandName::kTM));
  EXPECT_TRUE(AllowedInTimeAdjustMode(CommandName::kRS));
  EXPECT_TRUE(AllowedInTimeAdjustMode(CommandName::kRT));
  EXPECT_FALSE(AllowedInTimeAdjustMode(CommandName::kRB));
  EXPECT_FALSE(AllowedInTimeAdjustMode(CommandName::kScan));
  EXPECT_FALSE(AllowedInTimeAdjustMode(CommandName::kVV));
}

TEST(ScipCommandParser, InfoEncodersAreTheDecodersInverse) {
  const Version version{"Vendor", "Product", "1.2.3", "SCIP 2.0", "H123"};
  std::string vv = "VV\n";
  AppendStatusLine(vv, "00");
  AppendVersion(vv, version);
  vv += "\n";
  const auto decoded_version = DecodeVersion(ParseBlock(vv).value());
  ASSERT_TRUE(decoded_version.ok()) << decoded_version.error().message;
  EXPECT_EQ(decoded_version->vendor, "Vendor");
  EXPECT_EQ(decoded_version->product, "Product");
  EXPECT_EQ(decoded_version->firmware, "1.2.3");
  EXPECT_EQ(decoded_version->protocol, "SCIP 2.0");
  EXPECT_EQ(decoded_version->serial, "H123");
  const Parameters parameters{"UST-10LX", 20, 30000, 1440, 1, 1079, 541, 2400};
  std::string pp = "PP\n";
  AppendStatusLine(pp, "00");
  AppendParameters(pp, parameters);
  pp += "\n";
  const auto decoded = DecodeParameters(ParseBlock(pp).value());
  ASSERT_TRUE(decoded.ok()) << decoded.error().message;
  EXPECT_EQ(decoded->model, "UST-10LX");
  EXPECT_EQ(decoded->min_range_mm, 20);
  EXPECT_EQ(decoded->max_range_mm, 30000);
  EXPECT_EQ(decoded->steps_per_rotation, 1440);
  EXPECT_EQ(decoded->first_step, 1);
  EXPECT_EQ(decoded->last_step, 1079);
  EXPECT_EQ(decoded->front_step, 541);
  EXPECT_EQ(decoded->rotation_rpm, 2400);
}

}  // namespace
}  // namespace selfcal::scip
