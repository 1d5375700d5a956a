// Pure parts of the Wenglor driver: info XML, settings file (the picture counter and the clock
// mapping are tests/timing).
#include <gtest/gtest.h>

#include "drivers/wenglor/scanner_info.h"
#include "drivers/wenglor/wenglor_config.h"

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

TEST(WenglorConfig, ReadsKeysAndRejectsUnknownOnesAndBadValues) {
  auto config = ParseWenglorConfig(
      "library_path: /opt/lib.so\nip: 10.0.0.2\nport: '32002'\nexposure_time_us: 500\n"
      "line_time_us: 1000\ntrigger_source: encoder\nencoder_step: 4\nchannel: X\n",
      "wenglor.yaml");
  ASSERT_TRUE(config.ok()) << config.error().message;
  EXPECT_EQ(config->library_path, "/opt/lib.so");
  EXPECT_EQ(config->ip, "10.0.0.2");
  EXPECT_EQ(config->port, "32002");
  EXPECT_EQ(config->exposure_time_us, 500);
  EXPECT_EQ(config->line_time_us, 1000);
  EXPECT_EQ(config->trigger_source, TriggerSource::kEncoder);
  EXPECT_EQ(config->encoder_step, 4);
  EXPECT_EQ(config->channel, "X");
  EXPECT_EQ(config->data_timeout_ms, WenglorConfig{}.data_timeout_ms);

  auto unknown = ParseWenglorConfig("exposure: 5\n", "wenglor.yaml");
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.error().message.find("wenglor.yaml"), std::string::npos);
  EXPECT_NE(unknown.error().message.find("exposure"), std::string::npos);

  auto exposure = ParseWenglorConfig("exposure_time_us: 20\n", "w.yaml");
  ASSERT_FALSE(exposure.ok());
  EXPECT_NE(exposure.error().message.find("exposure_time_us"), std::string::npos);
  auto trigger = ParseWenglorConfig("trigger_source: laser\n", "w.yaml");
  ASSERT_FALSE(trigger.ok());
  EXPECT_NE(trigger.error().message.find("trigger_source"), std::string::npos);
  auto mistyped = ParseWenglorConfig("line_time_us: fast\n", "w.yaml");
  ASSERT_FALSE(mistyped.ok());
  EXPECT_NE(mistyped.error().message.find("line_time_us"), std::string::npos);
  EXPECT_FALSE(ParseWenglorConfig("signals_per_column: 3\n", "w.yaml").ok());
  EXPECT_FALSE(ParseWenglorConfig("line_time_us: 100\nexposure_time_us: 150\n", "w.yaml").ok());
}

}  // namespace
}  // namespace selfcal::wenglor
