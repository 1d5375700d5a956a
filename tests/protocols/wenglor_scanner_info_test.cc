// The Wenglor scanner's info XML (EthernetScanner_GetInfo): every field, millimetres to metres,
// and errors that name the element and its byte offset.
#include <gtest/gtest.h>

#include <string>

#include "protocols/wenglor/scanner_info.h"

namespace selfcal::wenglor {
namespace {

constexpr const char* kInfoXml =
    "<?xml version=\"1.0\"?>\n<info><general><ordernumber> MLSL236 </ordernumber>"
    "<serialnumber>A1</serialnumber></general><range>"
    "<workingrange_z_start>300</workingrange_z_start><measuringrange_z>1200</measuringrange_z>"
    "<fieldwidth_x_start>153.2</fieldwidth_x_start><fieldwidth_x_end>766</fieldwidth_x_end>"
    "<pixel_x_max>1280</pixel_x_max></range></info>";

TEST(ScannerInfo, ParsesEveryFieldAndConvertsMillimetres) {
  auto info = ParseScannerInfo(kInfoXml);
  ASSERT_TRUE(info.ok()) << info.error().message;
  EXPECT_EQ(info->order_number, "MLSL236");
  EXPECT_EQ(info->serial_number, "A1");
  EXPECT_DOUBLE_EQ(info->working_range_z_start, 0.300);
  EXPECT_DOUBLE_EQ(info->measuring_range_z, 1.200);
  EXPECT_DOUBLE_EQ(info->working_range_z_end(), 1.500);
  EXPECT_DOUBLE_EQ(info->field_width_x_start, 0.1532);
  EXPECT_DOUBLE_EQ(info->field_width_x_end, 0.766);
  EXPECT_EQ(info->pixel_x_max, 1280);
}

TEST(ScannerInfo, ErrorsNameTheElementAndOffset) {
  std::string xml = kInfoXml;
  auto missing = ParseScannerInfo("<info><pixel_x_max>1280</pixel_x_max></info>");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find("<ordernumber> missing"), std::string::npos);

  std::string bad_number = xml;
  bad_number.replace(bad_number.find(">1200<"), 6, ">12x0<");
  auto not_number = ParseScannerInfo(bad_number);
  ASSERT_FALSE(not_number.ok());
  const std::size_t offset = bad_number.find("12x0");
  EXPECT_NE(not_number.error().message.find("<measuringrange_z> at byte " + std::to_string(offset)),
            std::string::npos)
      << not_number.error().message;

  std::string unclosed = xml.substr(0, xml.find("</pixel_x_max>"));
  auto open = ParseScannerInfo(unclosed);
  ASSERT_FALSE(open.ok());
  EXPECT_NE(open.error().message.find("<pixel_x_max> at byte"), std::string::npos);
  EXPECT_NE(open.error().message.find("not closed"), std::string::npos);

  std::string fractional = xml;
  fractional.replace(fractional.find(">1280<"), 6, ">12.5<");
  EXPECT_FALSE(ParseScannerInfo(fractional).ok());
  EXPECT_FALSE(ParseScannerInfo("").ok());
  EXPECT_FALSE(ParseScannerInfo(std::string(100000, '<')).ok());
}

TEST(ScannerInfo, BadValuesSayWhereAndOversizedTextIsRefused) {
  const std::string xml = kInfoXml;
  std::string negative = xml;
  negative.replace(negative.find(">300<"), 5, ">-30<");
  auto minus = ParseScannerInfo(negative);
  ASSERT_FALSE(minus.ok());
  EXPECT_NE(minus.error().message.find("<workingrange_z_start> at byte " +
                                       std::to_string(negative.find("-30"))),
            std::string::npos)
      << minus.error().message;
  std::string zero_range = xml;
  zero_range.replace(zero_range.find(">1200<"), 6, ">0<");
  auto zero = ParseScannerInfo(zero_range);
  ASSERT_FALSE(zero.ok());
  EXPECT_NE(zero.error().message.find("<measuringrange_z> at byte"), std::string::npos);
  std::string oversized = xml;
  oversized.append(kMaxScannerInfoBytes, ' ');
  auto big = ParseScannerInfo(oversized);
  ASSERT_FALSE(big.ok());
  EXPECT_NE(big.error().message.find("exceeds the limit"), std::string::npos);
  // Every truncation of the document is an error, also one that keeps every field.
  for (std::size_t n = 0; n + 1 < xml.size(); ++n) {
    EXPECT_FALSE(ParseScannerInfo(std::string_view(xml).substr(0, n)).ok()) << n;
  }
  auto cut = ParseScannerInfo(xml.substr(0, xml.size() - 3));
  ASSERT_FALSE(cut.ok());
  EXPECT_NE(cut.error().message.find("root element at byte 22 is not closed"), std::string::npos)
      << cut.error().message;
}

}  // namespace
}  // namespace selfcal::wenglor
