// The start-up kit: options and their echo from one description, flags over a file, exit codes,
// the stop flag.
#include "protocols/program/program.h"

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <thread>
#include <vector>

namespace selfcal::program {
namespace {

enum class Mode { kFast, kExact };

struct Settings {
  std::string device = "/dev/ttyACM0";
  int port = 10940;
  double timeout_s = 0.5;
  bool usb = false;
  Mode mode = Mode::kExact;
  std::vector<double> position;
};

struct Args {
  explicit Args(std::vector<std::string> words) : words_(std::move(words)) {
    for (auto& word : words_) pointers_.push_back(word.data());
  }
  int argc() { return static_cast<int>(pointers_.size()); }
  char** argv() { return pointers_.data(); }
  std::vector<std::string> words_;
  std::vector<char*> pointers_;
};

void Describe(Program& program, Settings& s) {
  program.Option("--device", s.device, "Serial device");
  program.Option("--port", s.port, "TCP port");
  program.Option("--reply-timeout", s.timeout_s, "Reply timeout [s]");
  program.Flag("--usb", s.usb, "Use USB");
  program.Choice("--mode", s.mode, {{"fast", Mode::kFast}, {"exact", Mode::kExact}}, "Mode");
  program.Option("--position", s.position, "Joint positions [rad]");
}

TEST(Program, EchoesEveryOptionFromTheBoundValuesInOrder) {
  Program program("program-test", "test");
  Settings s;
  Describe(program, s);
  Args args({"program-test", "--port", "1234", "--mode", "fast", "--position", "1", "-2.5"});
  ASSERT_FALSE(program.Parse(args.argc(), args.argv()).has_value());
  EXPECT_EQ(s.port, 1234);
  EXPECT_EQ(s.mode, Mode::kFast);
  EXPECT_EQ(program.Configuration(),
            "device=/dev/ttyACM0 port=1234 reply_timeout=0.5 usb=false mode=fast position=1,-2.5");
  // The echo reads the variables, not the command line: a later change shows.
  s.device.clear();
  s.usb = true;
  program.EchoValue("joints", [] { return std::string("7"); });
  EXPECT_EQ(program.Configuration(),
            "device=\"\" port=1234 reply_timeout=0.5 usb=true mode=fast position=1,-2.5 joints=7");
}

TEST(Program, FlagsGivenOnTheCommandLineOverrideAFileReadAfterParsing) {
  Program program("program-test", "test");
  Settings s;
  Describe(program, s);
  Args args({"program-test", "--reply-timeout", "2", "--usb"});
  ASSERT_FALSE(program.Parse(args.argc(), args.argv()).has_value());
  // What a configuration file would set:
  s = Settings{};
  s.device = "/dev/ttyUSB3";
  s.port = 1;
  s.timeout_s = 9;
  program.ApplyCommandLineAgain();
  EXPECT_EQ(s.device, "/dev/ttyUSB3");
  EXPECT_EQ(s.port, 1);
  EXPECT_EQ(s.timeout_s, 2);
  EXPECT_TRUE(s.usb);
}

TEST(Program, HelpExitsZeroAndBadInputExitsWithUsageCode) {
  {
    Program program("program-test", "test");
    Settings s;
    Describe(program, s);
    Args args({"program-test", "--help"});
    testing::internal::CaptureStdout();
    EXPECT_EQ(program.Parse(args.argc(), args.argv()), std::optional<int>(kExitOk));
    const std::string help = testing::internal::GetCapturedStdout();
    EXPECT_NE(help.find("--reply-timeout"), std::string::npos) << help;
    EXPECT_NE(help.find("--verbose"), std::string::npos) << help;
  }
  for (std::vector<std::string> words :
       std::vector<std::vector<std::string>>{{"program-test", "--bogus"},
                                             {"program-test", "--port", "x"},
                                             {"program-test", "--mode", "slow"}}) {
    Program program("program-test", "test");
    Settings s;
    Describe(program, s);
    Args args(words);
    testing::internal::CaptureStderr();
    EXPECT_EQ(program.Parse(args.argc(), args.argv()), std::optional<int>(kExitUsage))
        << words.back();
    EXPECT_EQ(testing::internal::GetCapturedStderr().rfind("error: ", 0), 0u) << words.back();
  }
}

TEST(Program, ChecksSayWhatIsWrong) {
  struct Case {
    std::vector<std::string> words;
    std::string error;
  };
  for (const Case& c : std::vector<Case>{
           {{"program-test", "--mode", "slow"}, "error: --mode: 'slow' is not one of fast|exact\n"},
           {{"program-test", "--rpm", "0"}, "error: --rpm: must be positive, not 0\n"},
           {{"program-test", "--rpm", "x"}, "error: --rpm: 'x' is not a number\n"},
           {{"program-test", "--latency", "-1"},
            "error: --latency: must not be negative, not -1\n"},
       }) {
    Program program("program-test", "test");
    Settings s;
    Describe(program, s);
    double rpm = 1, latency = 0;
    program.Option("--rpm", rpm, "rpm")->check(kPositive);
    program.Option("--latency", latency, "latency")->check(kNonNegative);
    Args args(c.words);
    testing::internal::CaptureStderr();
    EXPECT_EQ(program.Parse(args.argc(), args.argv()), std::optional<int>(kExitUsage));
    EXPECT_EQ(testing::internal::GetCapturedStderr(), c.error);
  }
}

TEST(Program, AValidatorMayChooseItsExitCode) {
  Program program("program-test", "test");
  std::string path;
  program.Option("--config", path, "file")->check([](const std::string& value) -> std::string {
    throw BadInput(value + ": no such key 'exposure'", kExitFailure);
  });
  Args args({"program-test", "--config", "bad.yaml"});
  testing::internal::CaptureStderr();
  EXPECT_EQ(program.Parse(args.argc(), args.argv()), std::optional<int>(kExitFailure));
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "error: bad.yaml: no such key 'exposure'\n");
}

TEST(ProgramDeathTest, RejectsALongNameThatIsNotKebabCase) {
  EXPECT_DEATH(
      {
        Program program("program-test", "test");
        std::string url;
        program.Option("--lcm_url", url, "LCM URL");
      },
      "--lcm_url is not kebab-case");
}

// Subcommands (the selfcal command line) add their options through app(): Parse() checks them.
TEST(ProgramDeathTest, RejectsASubcommandOptionThatIsNotKebabCase) {
  EXPECT_DEATH(
      {
        Program program("program-test", "test");
        std::string robot;
        program.app().add_subcommand("calibrate", "")->add_option("--robot_model", robot, "");
        Args args({"program-test", "calibrate"});
        (void)program.Parse(args.argc(), args.argv());
      },
      "program-test calibrate: option --robot_model is not kebab-case");
  EXPECT_DEATH(
      {
        Program program("program-test", "test");
        program.app().add_subcommand("model_check", "");
        Args args({"program-test", "model_check"});
        (void)program.Parse(args.argc(), args.argv());
      },
      "program-test model_check: command name is not kebab-case");
}

TEST(Program, SubcommandsWithKebabCaseNamesParse) {
  Program program("program-test", "test");
  std::string robot;
  int scans = 0;
  CLI::App* command = program.app().add_subcommand("daemon-plan", "");
  command->add_option("--robot-model", robot, "");
  command->add_subcommand("nested", "")->add_option("--scan-count", scans, "");
  Args args({"program-test", "daemon-plan", "--robot-model", "r.yaml"});
  EXPECT_EQ(program.Parse(args.argc(), args.argv()), std::nullopt);
  EXPECT_EQ(robot, "r.yaml");
}

TEST(Program, FailPrintsTheReasonAndReturnsTheCode) {
  testing::internal::CaptureStderr();
  EXPECT_EQ(Fail("no device"), kExitFailure);
  EXPECT_EQ(Fail("bad flag", kExitUsage), kExitUsage);
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "error: no device\nerror: bad flag\n");
}

TEST(Program, SigtermSetsTheStopFlag) {
  std::atomic<bool>& stop = StopOnSignals();
  EXPECT_EQ(&stop, &StopFlag());
  EXPECT_FALSE(stop.load());
  std::raise(SIGTERM);
  EXPECT_TRUE(stop.load());
  stop.store(false);
  std::raise(SIGINT);
  EXPECT_TRUE(stop.load());
  stop.store(false);
}

TEST(Program, RunUntilStoppedEndsAfterTheDuration) {
  int steps = 0;
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(RunUntilStopped(0.05,
                            [&steps]() -> Status {
                              ++steps;
                              std::this_thread::sleep_for(std::chrono::milliseconds(1));
                              return OkStatus();
                            }),
            kExitOk);
  EXPECT_GE(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(50));
  EXPECT_GT(steps, 1);
}

TEST(Program, RunUntilStoppedEndsOnTheStopFlagAndOnAFailedStep) {
  int steps = 0;
  EXPECT_EQ(RunUntilStopped(0,
                            [&steps]() -> Status {
                              if (++steps == 3) std::raise(SIGINT);
                              return OkStatus();
                            }),
            kExitOk);
  EXPECT_EQ(steps, 3);
  StopFlag().store(false);
  testing::internal::CaptureStderr();
  EXPECT_EQ(RunUntilStopped(0, []() -> Status { return Error{"device gone"}; }), kExitFailure);
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "error: device gone\n");
}

TEST(Program, StandardBusOptionsEchoUnderTheirNames) {
  Program program("program-test", "test");
  std::string url;
  double duration_s = 0;
  program.LcmUrlOption(url);
  program.DurationOption(duration_s);
  Args args({"program-test", "--lcm-url", "memq://", "--duration", "2.5"});
  ASSERT_FALSE(program.Parse(args.argc(), args.argv()));
  EXPECT_EQ(program.Configuration(), "lcm_url=memq:// duration=2.5");
  EXPECT_NE(program.app().help().find("0: until SIGINT"), std::string::npos);
}

TEST(Program, MainParsesIntoTheSettingsThenStarts) {
  Args args({"program-test", "--port", "7", "--usb"});
  const int exit =
      Main<Settings>(args.argc(), args.argv(), {"program-test", "test"}, Describe,
                     [](Program& program, Settings& s) {
                       EXPECT_EQ(s.port, 7);
                       EXPECT_TRUE(s.usb);
                       EXPECT_NE(program.Configuration().find("port=7"), std::string::npos);
                       return 42;
                     });
  EXPECT_EQ(exit, 42);
}

TEST(Program, MainDoesNotStartAfterHelpOrBadInput) {
  bool started = false;
  auto start = [&started](Program&, Settings&) {
    started = true;
    return kExitOk;
  };
  Args help({"program-test", "--help"});
  testing::internal::CaptureStdout();
  EXPECT_EQ(Main<Settings>(help.argc(), help.argv(), {"program-test", "test"}, Describe, start),
            kExitOk);
  (void)testing::internal::GetCapturedStdout();
  Args bad({"program-test", "--port", "many"});
  testing::internal::CaptureStderr();
  EXPECT_EQ(Main<Settings>(bad.argc(), bad.argv(), {"program-test", "test"}, Describe, start),
            kExitUsage);
  (void)testing::internal::GetCapturedStderr();
  EXPECT_FALSE(started);
}

TEST(Program, OpenBusNamesTheUrlOnFailure) {
  Program program("program-test", "test");
  auto bus = program.OpenBus("bogus://nowhere");
  ASSERT_FALSE(bus.ok());
  EXPECT_NE(bus.error().message.find("bogus://nowhere"), std::string::npos);
  auto memq = program.OpenBus("memq://");
  ASSERT_TRUE(memq.ok()) << memq.error().message;
}

}  // namespace
}  // namespace selfcal::program
