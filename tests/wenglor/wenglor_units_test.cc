// Pure parts of the Wenglor driver: the settings file (the info XML is
// tests/protocols/wenglor_scanner_info_test.cc, the picture counter and the clock mapping are
// tests/timing).
#include <gtest/gtest.h>

#include "drivers/wenglor/wenglor_config.h"

namespace selfcal::wenglor {
namespace {

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
