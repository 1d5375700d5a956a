// The command line of the streaming depth cameras' stream options.
#include "protocols/camera/stream_options.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace selfcal::camera {
namespace {

struct Args {
  explicit Args(std::vector<std::string> words) : words_(std::move(words)) {
    for (auto& word : words_) pointers_.push_back(word.data());
  }
  int argc() { return static_cast<int>(pointers_.size()); }
  char** argv() { return pointers_.data(); }
  std::vector<std::string> words_;
  std::vector<char*> pointers_;
};

TEST(DescribeRequestStreamOptions, BindsAndEchoesInOrder) {
  program::Program program("stream-options-test", "test");
  std::string lcm_url;
  std::string trigger = "none";
  StreamOptions stream{.channel = "DEPTH"};
  DescribeRequestStreamOptions(program, lcm_url, trigger, stream);
  Args args({"stream-options-test", "--lcm-url", "memq://", "--trigger", "request",
             "--trigger-channel", "MARKER", "--max-frames", "3"});
  ASSERT_FALSE(program.Parse(args.argc(), args.argv()).has_value());
  EXPECT_EQ(lcm_url, "memq://");
  EXPECT_EQ(trigger, "request");
  EXPECT_EQ(stream.channel, "DEPTH");
  EXPECT_EQ(stream.trigger_channel, "MARKER");
  EXPECT_EQ(stream.max_frames, 3);
  EXPECT_EQ(program.Configuration(),
            "lcm_url=memq:// channel=DEPTH trigger=request trigger_channel=MARKER max_frames=3");
}

TEST(DescribeRequestStreamOptions, RejectsAnUnknownTrigger) {
  program::Program program("stream-options-test", "test");
  std::string lcm_url;
  std::string trigger = "none";
  StreamOptions stream;
  DescribeRequestStreamOptions(program, lcm_url, trigger, stream);
  Args args({"stream-options-test", "--trigger", "hardware"});
  EXPECT_EQ(program.Parse(args.argc(), args.argv()), std::optional<int>(program::kExitUsage));
}

}  // namespace
}  // namespace selfcal::camera
