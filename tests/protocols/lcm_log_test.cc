// The LCM log reader on what is not a complete log: a folder, a text file, an empty file and a
// log cut off inside its last event.
#include "protocols/lcm_log/lcm_log.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace selfcal {
namespace {

class LcmLogTest : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ = std::filesystem::temp_directory_path() /
                 ("selfcal_lcm_log_test_" + std::to_string(getpid()) + "_" +
                  ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(directory_);
  }
  void TearDown() override { std::filesystem::remove_all(directory_); }
  std::string Path(const std::string& name) const { return (directory_ / name).string(); }

  // Three events of 100 data bytes on channel "A".
  void WriteLog(const std::string& path) {
    auto writer = LcmLogWriter::Open(path);
    ASSERT_TRUE(writer.ok()) << writer.error().message;
    for (int i = 0; i < 3; ++i) {
      ASSERT_TRUE(writer->Write("A", 1000 + i, std::vector<std::uint8_t>(100, 7)).ok());
    }
    ASSERT_TRUE(writer->Commit().ok());
  }

  std::filesystem::path directory_;
};

TEST_F(LcmLogTest, AFolderIsNamedAsAFolder) {
  const auto reader = LcmLogReader::Open(directory_.string());
  ASSERT_FALSE(reader.ok());
  EXPECT_EQ(reader.error().message, directory_.string() + ": is a folder, not an LCM log");
}

TEST_F(LcmLogTest, AFileWithoutTheSyncWordIsNotAnLcmLog) {
  const std::string path = Path("truth.yaml");
  std::ofstream(path) << "name: kuka_lbr_iiwa_r840\njoints: []\n";
  const auto reader = LcmLogReader::Open(path);
  ASSERT_FALSE(reader.ok());
  EXPECT_EQ(reader.error().message,
            path + ": not an LCM log (it does not begin with the event sync word 0xEDA1DA01)");
}

TEST_F(LcmLogTest, AnEmptyFileIsAnEmptyLog) {
  const std::string path = Path("empty.lcmlog");
  std::ofstream{path};
  auto reader = LcmLogReader::Open(path);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  LogEvent event;
  EXPECT_FALSE(reader->Next(event));
  EXPECT_EQ(reader->torn_bytes(), 0);
}

TEST_F(LcmLogTest, ATornLastEventIsCounted) {
  const std::string path = Path("cut.lcmlog");
  WriteLog(path);
  {
    auto reader = LcmLogReader::Open(path);
    ASSERT_TRUE(reader.ok());
    LogEvent event;
    int events = 0;
    while (reader->Next(event)) ++events;
    EXPECT_EQ(events, 3);
    EXPECT_EQ(reader->torn_bytes(), 0);  // a complete log ends cleanly
  }
  const auto size = std::filesystem::file_size(path);
  const std::uintmax_t event_bytes = 4 + 8 + 8 + 4 + 4 + 1 + 100;  // sync, header, "A", data
  ASSERT_EQ(size, 3 * event_bytes);
  std::filesystem::resize_file(path, size - 40);
  auto reader = LcmLogReader::Open(path);
  ASSERT_TRUE(reader.ok());
  LogEvent event;
  int events = 0;
  while (reader->Next(event)) ++events;
  EXPECT_EQ(events, 2);
  EXPECT_EQ(reader->torn_bytes(), static_cast<std::int64_t>(event_bytes - 40));
}

}  // namespace
}  // namespace selfcal
