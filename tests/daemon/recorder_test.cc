// The session recorder: a committed log is complete and readable, a discarded one stays
// .partial, and a write error is kept for the daemon instead of being lost in a bus handler.
#include "daemon/recorder.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <csignal>
#include <filesystem>
#include <vector>

#include "selfcal/scan_marker_t.hpp"

namespace selfcal::daemon {
namespace {

namespace fs = std::filesystem;

std::string TempDir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("selfcal_recorder_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

TEST(RecorderTest, CommitMakesTheLogAndDiscardLeavesItPartial) {
  const std::string dir = TempDir("commit");
  Recorder recorder;
  EXPECT_FALSE(recorder.recording());
  ASSERT_TRUE(recorder.Open(dir + "/a.lcmlog"));
  EXPECT_TRUE(recorder.recording());
  const std::vector<std::uint8_t> bytes = {1, 2, 3};
  recorder.Write("RAW", 10, bytes);
  selfcal::scan_marker_t marker{};
  marker.session_id = "S";
  recorder.Write("MARKER", 11, marker);
  EXPECT_EQ(recorder.error(), "");
  ASSERT_TRUE(recorder.Commit());
  EXPECT_FALSE(recorder.recording());
  auto log = LcmLogReader::Open(dir + "/a.lcmlog");
  ASSERT_TRUE(log) << log.error().message;
  LogEvent event;
  std::vector<std::string> channels;
  while (log->Next(event)) channels.push_back(event.channel);
  EXPECT_EQ(channels, (std::vector<std::string>{"RAW", "MARKER"}));

  ASSERT_TRUE(recorder.Open(dir + "/b.lcmlog"));
  recorder.Write("RAW", 12, bytes);
  recorder.Discard();
  EXPECT_FALSE(recorder.recording());
  EXPECT_FALSE(fs::exists(dir + "/b.lcmlog"));
  EXPECT_TRUE(fs::exists(dir + "/b.lcmlog.partial"));
  EXPECT_FALSE(recorder.Commit()) << "nothing is open";
  recorder.Write("RAW", 13, bytes);  // ignored while closed
  fs::remove_all(dir);
}

TEST(RecorderTest, AWriteErrorIsKeptAndLaterWritesAreDropped) {
  const std::string dir = TempDir("full");
  // A full disk, as in the process test: writes beyond 64 KiB fail with EFBIG.
  std::signal(SIGXFSZ, SIG_IGN);
  rlimit before{};
  getrlimit(RLIMIT_FSIZE, &before);
  rlimit limit = before;
  limit.rlim_cur = 64 * 1024;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &limit), 0);
  Recorder recorder;
  ASSERT_TRUE(recorder.Open(dir + "/full.lcmlog"));
  const std::vector<std::uint8_t> bytes(16 * 1024, 7);
  for (int i = 0; i < 16 && recorder.error().empty(); ++i) recorder.Write("RAW", i, bytes);
  const std::string error = recorder.error();
  for (int i = 0; i < 4; ++i) recorder.Write("RAW", 100 + i, bytes);
  setrlimit(RLIMIT_FSIZE, &before);
  EXPECT_NE(error, "") << "the 64 KiB limit was never hit";
  EXPECT_EQ(recorder.error(), error) << "the first error is the one kept";
  recorder.Discard();
  EXPECT_EQ(recorder.error(), "") << "a new recording starts clean";
  fs::remove_all(dir);
}

}  // namespace
}  // namespace selfcal::daemon
