// Bad input: truncated, corrupted, oversized and junk-interleaved replies return errors that
// say where (stream byte offset), and the framer resynchronises on the next block.
#include <gtest/gtest.h>

#include <string>

#include "protocols/scip/block.h"
#include "protocols/scip/encoding.h"
#include "protocols/scip/replies.h"

namespace selfcal::scip {
namespace {

std::string MdScan(std::uint32_t timestamp, int steps, std::uint32_t base = 1000) {
  std::string echo = "MD0000" + std::string(4 - std::to_string(steps - 1).size(), '0') +
                     std::to_string(steps - 1) + "01000";
  std::string out = echo + "\n";
  AppendStatusLine(out, "99");
  ScanValues values;
  values.timestamp_ms = timestamp;
  for (int i = 0; i < steps; ++i) values.ranges_mm.push_back(base + static_cast<std::uint32_t>(i));
  AppendScanData(out, ScanType::kMD, values);
  out += "\n";
  return out;
}

Status DecodeBytes(std::string_view bytes, std::uint64_t offset = 0) {
  auto block = ParseBlock(bytes, offset);
  if (!block) return block.error();
  auto echo = ParseScanEcho(block->echo);
  // The driver names where a bad echo was, as here.
  if (!echo) return Error{"byte " + std::to_string(offset) + ": " + echo.error().message};
  ScanData scan;
  return DecodeScan(*block, *echo, scan);
}

bool Mentions(const Status& status, std::string_view text) {
  return !status.ok() && status.error().message.find(text) != std::string::npos;
}

TEST(ScipErrors, GoodScanDecodes) { EXPECT_TRUE(DecodeBytes(MdScan(77, 100)).ok()); }

TEST(ScipErrors, EveryTruncationIsAnError) {
  const std::string scan = MdScan(77, 100);
  for (std::size_t size = 0; size + 1 < scan.size(); ++size) {
    const std::string cut = scan.substr(0, size) + "\n";  // a cut line ends where it stops
    EXPECT_FALSE(DecodeBytes(cut).ok()) << "size " << size;
  }
}

TEST(ScipErrors, MissingLineSaysValueIndex) {
  std::string scan = MdScan(77, 100);
  // Drop the last data line entirely (a line the sensor never sent).
  const std::size_t last = scan.rfind('\n', scan.size() - 3);
  const std::string cut = scan.substr(0, last + 1) + "\n";
  const auto status = DecodeBytes(cut, 1000);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.error().message.find("ends in value"), std::string::npos)
      << status.error().message;
}

TEST(ScipErrors, EveryFlippedByteIsCaughtWithItsOffset) {
  const std::string scan = MdScan(77, 100);
  const std::size_t echo_end = scan.find('\n');
  int caught = 0;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    for (const int bit : {0x01, 0x10}) {
      std::string bad = scan;
      bad[i] = static_cast<char>(bad[i] ^ bit);
      auto block = ParseBlock(bad, 5000);
      ScanData scan_data;
      Status status = block ? Status(OkStatus()) : Status(block.error());
      if (block) {
        auto echo = ParseScanEcho(block->echo);
        status = echo ? DecodeScan(*block, *echo, scan_data) : Status(echo.error());
      }
      if (i < echo_end) {
        // The echo carries no checksum (SCIP 2.0): a flip there either fails to parse or changes
        // only fields that do not alter the data (cluster 01 -> 00, the remaining count).
        if (status.ok()) {
          ASSERT_EQ(scan_data.ranges_mm.size(), 100u) << "flip at " << i;
          EXPECT_EQ(scan_data.ranges_mm[99], 1099u);
        }
        continue;
      }
      // Payload byte: its line's sum; LF: the framing; checksum: the sum. Never decodes.
      EXPECT_FALSE(status.ok()) << "flip at " << i;
      if (!status.ok() && status.error().message.starts_with("byte ")) ++caught;
    }
  }
  EXPECT_EQ(caught, 2 * static_cast<int>(scan.size() - echo_end));
}

TEST(ScipErrors, ChecksumErrorNamesTheLineOffset) {
  std::string scan = MdScan(77, 100);
  const std::size_t second_data_line = scan.find('\n', scan.find("\n99b\n") + 5) + 1;
  scan[second_data_line + 3] = static_cast<char>(scan[second_data_line + 3] + 1);
  const auto status = DecodeBytes(scan, 10000);
  ASSERT_FALSE(status.ok());
  // The error points at the checksum character of that line.
  const std::size_t checksum_at = scan.find('\n', second_data_line) - 1;
  EXPECT_TRUE(Mentions(status, "byte " + std::to_string(10000 + checksum_at)))
      << status.error().message;
  EXPECT_TRUE(Mentions(status, "checksum mismatch"));
}

TEST(ScipErrors, BadCharacterWithGoodChecksumNamesTheValue) {
  // A sensor (or a fuzzer) may send a character outside the alphabet with a matching sum.
  std::string out = "MD0000000401000\n99b\n";
  AppendDataLine(out, "0000");
  AppendDataLine(out, "0000000p0000000");  // value 2 holds 'p'
  out += "\n";
  const auto status = DecodeBytes(out, 0);
  ASSERT_FALSE(status.ok());
  EXPECT_TRUE(Mentions(status, "value 2")) << status.error().message;
  EXPECT_TRUE(Mentions(status, "byte " + std::to_string(out.find("0000000p") + 6)))
      << status.error().message;
}

TEST(ScipErrors, TooManyValuesAndOversizedLines) {
  std::string scan = MdScan(77, 10);
  // Ask for 5 values in the echo but send 10.
  scan.replace(0, 15, "MD0000000401000");
  EXPECT_TRUE(Mentions(DecodeBytes(scan), "more than the 5 values"));

  std::string long_line = "MD0000108001000\n99b\n";
  AppendDataLine(long_line, "0000");
  AppendDataLine(long_line, std::string(65, '0'));
  long_line += "\n";
  EXPECT_TRUE(Mentions(DecodeBytes(long_line), "exceeds 64"));

  const std::string long_echo = std::string(80, 'M') + "\n00P\n\n";
  EXPECT_TRUE(Mentions(DecodeBytes(long_echo), "echo line of 80"));
}

TEST(ScipErrors, OversizedBlockIsDroppedAndTheStreamContinues) {
  BlockFramer framer(/*max_block_bytes=*/512);
  framer.Append(MdScan(1, 1000));  // ~3 kB: above the limit
  framer.Append(MdScan(2, 20));
  auto first = framer.Next();
  ASSERT_TRUE(first.has_value());
  ASSERT_FALSE(first->ok());
  EXPECT_NE(first->error().message.find("exceeds the limit"), std::string::npos);
  auto second = framer.Next();
  ASSERT_TRUE(second.has_value() && second->ok()) << second->error().message;

  // Junk without any empty line is bounded too.
  framer.Append(std::string(2000, 'x'));
  auto junk = framer.Next();
  ASSERT_TRUE(junk.has_value());
  EXPECT_FALSE(junk->ok());
  EXPECT_NE(junk->error().message.find("no block end"), std::string::npos);
  framer.Append("\n" + MdScan(3, 20));
  auto next = framer.Next();
  // The junk's tail and the first line form a broken block; then the stream is clean again.
  while (next.has_value() && !next->ok()) next = framer.Next();
  ASSERT_TRUE(next.has_value());
  EXPECT_EQ(ParseScanEcho((*next)->echo)->request.end_step, 19);
}

TEST(ScipErrors, JunkInterleavedBetweenAndInsideBlocks) {
  const std::string a = MdScan(10, 50, 1000);
  const std::string b = MdScan(35, 50, 2000);
  const std::string c = MdScan(60, 50, 3000);
  // Junk between a and b (glued to b's echo), and a junk line inside c.
  std::string c_bad = c;
  c_bad.insert(c.find("\n99b\n") + 5, "GARBAGE\n");
  const std::string stream = a + "\x01\x02zz" + b + c_bad + a;
  BlockFramer framer;
  framer.Append(stream);
  std::vector<std::string> results;
  while (auto block = framer.Next()) {
    if (!block->ok()) {
      results.push_back("error: " + block->error().message);
      continue;
    }
    auto echo = ParseScanEcho((*block)->echo);
    ScanData scan;
    const auto status = echo ? DecodeScan(**block, *echo, scan) : Status(echo.error());
    results.push_back(status.ok() ? "scan " + std::to_string(scan.timestamp_ms)
                                  : "error: " + status.error().message);
  }
  ASSERT_EQ(results.size(), 4u);
  EXPECT_EQ(results[0], "scan 10");
  EXPECT_NE(results[1].find("byte " + std::to_string(a.size())), std::string::npos) << results[1];
  EXPECT_NE(results[2].find("byte " +
                            std::to_string(a.size() + 4 + b.size() + c.find("\n99b\n") + 5 + 6)),
            std::string::npos)
      << results[2];
  EXPECT_EQ(results[3], "scan 10");
}

TEST(ScipErrors, InfoAndTimeReplies) {
  EXPECT_FALSE(DecodeParameters(*ParseBlock("PP\n00P\nDMIN:23;7\n\n")).ok());
  const auto bad_number =
      DecodeParameters(*ParseBlock("PP\n00P\nMODL:X;" + std::string(1, Checksum("MODL:X")) +
                                   "\nDMIN:2x;" + std::string(1, Checksum("DMIN:2x")) + "\n\n"));
  ASSERT_FALSE(bad_number.ok());
  EXPECT_NE(bad_number.error().message.find("DMIN"), std::string::npos);
  EXPECT_FALSE(DecodeTime(*ParseBlock("TM1\n00P\n\n")).ok());
  EXPECT_FALSE(DecodeTime(*ParseBlock("TM1\n04T\n\n")).ok());
  EXPECT_FALSE(ParseScanEcho("MD00001080010").ok());
  EXPECT_FALSE(ParseScanEcho("MD000010800100x").ok());
  EXPECT_FALSE(ParseScanEcho("XX0000108001000").ok());
  EXPECT_FALSE(ParseScanEcho("MD1080000001000").ok());
  const auto tagged = ParseScanEcho("MD0000108001000;abc");
  ASSERT_TRUE(tagged.ok());
  EXPECT_EQ(tagged->tag, "abc");
}

}  // namespace
}  // namespace selfcal::scip
