// Pure parts of the Wenglor driver: the settings file, the column decoding (the info XML is
// tests/protocols/wenglor_scanner_info_test.cc, the picture counter and the clock mapping are
// tests/timing).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "drivers/wenglor/wenglor_config.h"
#include "drivers/wenglor/wenglor_scanner.h"

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

// Found by fuzz_wenglor_profile: a library buffer with -inf (or NaN, or 1e300) mm was published
// as a coordinate (1e300 also overflowed the float conversion).
TEST(WenglorDecode, ColumnsWithoutAFinitePlausibleCoordinateAreNoReturn) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
  // Two signals per column: signal 1 at even indices, signal 2 (ignored) at odd ones.
  const std::vector<double> x = {10, 99, 0, 99, 5, 99, kNan, 99, 1e300, 99, -20, 99};
  const std::vector<double> z = {200, 99, 0, 99, -kInf, 99, 300, 99, 300, 99, 250, 99};
  const std::vector<int> intensity = {1, 0, 2, 0, 3, 0, 4, 0, 5, 0, 6, 0};
  const std::vector<int> peak = {7, 0, 7, 0, 7, 0, 7, 0, 7, 0, 7, 0};
  Profile profile;
  profile.Allocate(8);
  DecodeColumns(x, z, intensity, peak, 6, 2, profile);
  ASSERT_EQ(profile.num_points, 6);
  EXPECT_FLOAT_EQ(profile.x[0], 0.010f);
  EXPECT_FLOAT_EQ(profile.z[0], 0.200f);
  for (const std::size_t no_return : {1u, 2u, 3u, 4u}) {  // 0/0, -inf, NaN, 1e300
    EXPECT_TRUE(std::isnan(profile.x[no_return]) && std::isnan(profile.z[no_return]))
        << "column " << no_return << ": " << profile.x[no_return] << ", " << profile.z[no_return];
  }
  EXPECT_FLOAT_EQ(profile.x[5], -0.020f);
  EXPECT_FLOAT_EQ(profile.z[5], 0.250f);
  EXPECT_EQ(profile.intensity[5], 6.0f);
  EXPECT_EQ(profile.peak_width[2], 7.0f);
}

}  // namespace
}  // namespace selfcal::wenglor
