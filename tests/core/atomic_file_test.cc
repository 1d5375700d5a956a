#include "core/util/atomic_file.h"

#include <gtest/gtest.h>

#include <filesystem>

namespace selfcal {
namespace {

std::filesystem::path TempFolder() {
  auto folder =
      std::filesystem::temp_directory_path() / ("selfcal_atomic_" + std::to_string(::getpid()));
  std::filesystem::create_directories(folder);
  return folder;
}

TEST(AtomicFile, ReplacesContentsAndLeavesNoTemporary) {
  const auto folder = TempFolder();
  const std::string path = (folder / "model.yaml").string();
  ASSERT_TRUE(WriteFileAtomically(path, "old").ok());
  ASSERT_TRUE(WriteFileAtomically(path, "new contents").ok());
  EXPECT_EQ(ReadFile(path).value(), "new contents");
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(folder)) ++files;
  EXPECT_EQ(files, 1u);
  std::filesystem::remove_all(folder);
}

TEST(AtomicFile, FailureKeepsTheOldFileAndNamesThePath) {
  const auto folder = TempFolder();
  const std::string path = (folder / "missing_folder" / "model.yaml").string();
  const auto status = WriteFileAtomically(path, "x");
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.error().message.find("missing_folder"), std::string::npos);
  const auto read = ReadFile(path);
  ASSERT_FALSE(read.ok());
  EXPECT_NE(read.error().message.find(path), std::string::npos);
  std::filesystem::remove_all(folder);
}

TEST(AtomicFile, ReadRejectsOversizedFiles) {
  const auto folder = TempFolder();
  const std::string path = (folder / "big").string();
  ASSERT_TRUE(WriteFileAtomically(path, std::string(100, 'x')).ok());
  const auto read = ReadFile(path, 10);
  ASSERT_FALSE(read.ok());
  EXPECT_NE(read.error().message.find("100 bytes"), std::string::npos);
  std::filesystem::remove_all(folder);
}

}  // namespace
}  // namespace selfcal
