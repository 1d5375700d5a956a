// selfcal-hokuyo's configuration file: the shipped example reads, strictly.
#include "drivers/hokuyo/config.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

namespace selfcal::hokuyo {
namespace {

std::string Write(const std::string& text) {
  const std::string path = "/tmp/selfcal-hokuyo-config-" + std::to_string(getpid()) + ".yaml";
  std::ofstream(path) << text;
  return path;
}

TEST(HokuyoConfigFile, TheShippedExampleReads) {
  ProcessConfig config = DefaultProcessConfig();
  const std::string path =
      std::string(std::getenv("SELFCAL_SOURCE_DIR")) + "/config/drivers/hokuyo.yaml";
  const auto status = ReadProcessConfig(path, config);
  ASSERT_TRUE(status.ok()) << status.error().message;
  EXPECT_EQ(config.driver.device, "/dev/ttyACM0");
  EXPECT_EQ(config.driver.port, 10940);
  EXPECT_EQ(config.driver.scan_type, scip::ScanType::kMD);
  EXPECT_EQ(config.driver.sync_interval_s, 0.02);
  EXPECT_EQ(config.channel, "SELFCAL_RANGE_SCAN");
  EXPECT_TRUE(HokuyoDriver::Validate(config.driver).ok());
}

TEST(HokuyoConfigFile, UnknownKeysAndBadValuesNameFileAndKey) {
  ProcessConfig config = DefaultProcessConfig();
  const std::string unknown = Write("host: 10.0.0.2\nbaudrate: 9600\n");
  auto status = ReadProcessConfig(unknown, config);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.error().message.find(unknown), std::string::npos) << status.error().message;
  EXPECT_NE(status.error().message.find("baudrate"), std::string::npos) << status.error().message;

  const std::string wrong_type = Write("port: ten\n");
  status = ReadProcessConfig(wrong_type, config);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.error().message.find("port"), std::string::npos) << status.error().message;

  const std::string bad_type = Write("scan_type: GD\n");
  status = ReadProcessConfig(bad_type, config);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.error().message.find("scan_type"), std::string::npos);

  const std::string good = Write("host: 10.0.0.2\nscan_type: ME\nskip: 2\n");
  config = DefaultProcessConfig();
  ASSERT_TRUE(ReadProcessConfig(good, config).ok());
  EXPECT_EQ(config.driver.host, "10.0.0.2");
  EXPECT_EQ(config.driver.scan_type, scip::ScanType::kME);
  EXPECT_EQ(config.driver.skip, 2);
  std::remove(good.c_str());
}

}  // namespace
}  // namespace selfcal::hokuyo
