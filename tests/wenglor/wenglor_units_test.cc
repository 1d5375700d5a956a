// Pure parts of the Wenglor driver: info XML, picture counter, clock mapping, settings file.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "drivers/wenglor/clock_mapper.h"
#include "drivers/wenglor/picture_counter.h"
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

TEST(PictureCounter, ConsecutiveWrapGapRepeatRestart) {
  PictureCounter counter;
  auto step = counter.Update(65533);
  EXPECT_EQ(step.unwrapped, 65533);
  EXPECT_EQ(step.lost, 0);
  step = counter.Update(65534);
  EXPECT_EQ(step.lost, 0);
  step = counter.Update(65535);
  step = counter.Update(0);  // wrap
  EXPECT_EQ(step.unwrapped, 65536);
  EXPECT_EQ(step.lost, 0);
  step = counter.Update(1);
  EXPECT_EQ(step.unwrapped, 65537);
  step = counter.Update(6);  // 4 lost
  EXPECT_EQ(step.lost, 4);
  EXPECT_EQ(step.unwrapped, 65542);
  step = counter.Update(6);
  EXPECT_TRUE(step.repeated);
  EXPECT_EQ(step.lost, 0);
  step = counter.Update(65530);  // more than half the range ahead: read as going backwards
  EXPECT_TRUE(step.restarted);
  EXPECT_EQ(step.lost, 0);
  EXPECT_EQ(step.unwrapped, 65543);
  step = counter.Update(3);  // 65531 .. 2 lost across the wrap: 8 lost
  EXPECT_EQ(step.lost, 8);
  counter.Reset();
  step = counter.Update(100);
  EXPECT_EQ(step.unwrapped, 100);
  EXPECT_EQ(step.lost, 0);
}

TEST(ClockMapper, FollowsTheLowestLatencyAndNeverPassesTheReceiveTime) {
  ClockMapper mapper(/*max_drift_ppm=*/100);
  const std::int64_t true_offset = 1'700'000'000'000'000;
  // Latencies: 900, 300, 2000, 50, 700 us; device ticks of 1 ms.
  const std::int64_t latency[] = {900, 300, 2000, 50, 700, 5000, 60};
  for (int k = 0; k < 7; ++k) {
    const std::int64_t device = k * 1000;
    const std::int64_t host = device + true_offset + latency[k];
    const std::int64_t mapped = mapper.Map(device, host);
    EXPECT_LE(mapped, host);
    EXPECT_GE(mapped, device + true_offset);  // the bias is never negative
  }
  // After the 50 us sample the error is 50 us plus at most 100 ppm of the elapsed device time.
  EXPECT_LE(mapper.offset_us() - static_cast<double>(true_offset), 50 + 100e-6 * 3000 + 1);
}

TEST(ClockMapper, TracksASlowDeviceClockWithinTheDriftBound) {
  // The device clock runs 50 ppm slow: host - device grows 50 us per second.
  ClockMapper mapper(/*max_drift_ppm=*/100);
  double worst = 0;
  for (int k = 0; k < 20000; ++k) {  // 20 s at 1 kHz, constant 100 us latency
    const std::int64_t device = k * 1000;
    const auto host = static_cast<std::int64_t>(static_cast<double>(device) * (1 + 50e-6)) + 100;
    const std::int64_t mapped = mapper.Map(device, host);
    const double truth = static_cast<double>(device) * (1 + 50e-6);
    worst = std::max(worst, std::abs(static_cast<double>(mapped) - truth));
  }
  // Without the drift allowance the error would grow to 1000 us; with it, it stays at the latency.
  EXPECT_LE(worst, 102);
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
