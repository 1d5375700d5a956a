// The start-up kit of every selfcal program: command line (CLI11) and its exit codes, one logger,
// the stop flag set by SIGINT/SIGTERM, opening the bus, and the effective configuration printed
// from the same description that defines the options, so that the echo cannot drift from them.
//
//   selfcal::program::Program program("selfcal-foo", "what it does");
//   program.Option("--lcm-url", options.lcm_url, "LCM URL");
//   if (auto exit = program.Parse(argc, argv)) return *exit;
//   program.LogConfiguration();
//   auto bus = program.OpenBus(options.lcm_url);
//   if (!bus) return program::Fail(bus.error().message);
//   return program::ExitCode(Run(options, **bus, program::StopOnSignals()));
// or, for most programs, program::Main below.
#pragma once

#include <CLI/CLI.hpp>
#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/util/expected.h"
#include "core/util/log.h"
#include "protocols/bus/bus.h"

namespace selfcal::program {

// Exit codes: bad command-line input is kExitUsage; a failure after start is kExitFailure.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;
inline constexpr int kExitUsage = 2;

// Prints "error: <reason>" on stderr and returns `exit_code`.
int Fail(std::string_view reason, int exit_code = kExitFailure);
// kExitOk for a good status, else Fail() with its error: the last line of a program that ran.
int ExitCode(const Status& status);

// Thrown by an option's check or callback (reading the --config file, say): Parse() prints
// "error: <message>" and returns `exit_code`.
class BadInput : public CLI::ParseError {
 public:
  explicit BadInput(const std::string& message, int exit_code = kExitUsage)
      : CLI::ParseError("BadInput", message, exit_code) {}
};

// The process's stop flag: false until SIGINT or SIGTERM arrives after StopOnSignals().
std::atomic<bool>& StopFlag();
// Installs the SIGINT and SIGTERM handlers that set StopFlag(), and returns it.
std::atomic<bool>& StopOnSignals();

// Calls `step` until a stop signal arrives (installs StopOnSignals()), `step` fails or
// `duration_s` seconds have passed (0: no limit). Returns kExitOk, or Fail()'s code with the
// step's error: the run loop and exit path of every program that spins a driver or simulator.
int RunUntilStopped(double duration_s, const std::function<Status()>& step);

// Forwards library log messages to the program's logger (spdlog, on stderr).
LogSink Logger();
// Logs one message at `level` through the program's logger.
void Log(LogLevel level, const std::string& message);

// Formats a value for the configuration echo: numbers as printed by iostreams, booleans as
// true/false, sequences comma-separated, an empty string as "".
template <typename T>
std::string FormatValue(const T& value) {
  std::ostringstream out;
  if constexpr (std::is_same_v<T, bool>) {
    out << (value ? "true" : "false");
  } else if constexpr (std::is_same_v<T, std::string>) {
    out << (value.empty() ? std::string("\"\"") : value);
  } else if constexpr (requires {
                         value.begin();
                         value.end();
                       }) {
    const char* separator = "";
    for (const auto& element : value) {
      out << separator << FormatValue(element);
      separator = ",";
    }
  } else {
    out << value;
  }
  return out.str();
}

// Where `cmake --install` put config/ (SYSCONFDIR/selfcal), joined with `relative`: the default
// of every option that names a configuration file.
std::string InstalledConfig(const std::string& relative);

// Checks for numeric options, with messages that say what is wrong ("--rpm: must be positive,
// not 0").
extern const CLI::Validator kPositive;
extern const CLI::Validator kNonNegative;

// What a program is: the executable's name (the logger's too) and the text that heads --help.
struct About {
  const char* name;
  const char* description;
};

class Program {
 public:
  // `name` is the executable's name, used for the logger; `description` heads --help.
  Program(std::string name, const std::string& description);
  explicit Program(const About& about) : Program(about.name, about.description) {}

  CLI::App& app() { return app_; }
  const std::string& name() const { return name_; }

  // Adds an option bound to `value` and echoes it under its long name in snake_case
  // (--lcm-url as lcm_url). `names` is CLI11's ("-c,--config"); long names are kebab-case
  // (checked).
  template <typename T>
  CLI::Option* Option(const std::string& names, T& value, const std::string& help) {
    CLI::Option* option = app_.add_option(names, value, help)->capture_default_str();
    Echo(option, [&value] { return FormatValue(value); });
    return option;
  }
  CLI::Option* Flag(const std::string& names, bool& value, const std::string& help);
  // The standard options of bus programs, with one help text each: --lcm-url (empty: the
  // environment's or liblcm's default) and --duration (seconds, 0: until SIGINT).
  CLI::Option* LcmUrlOption(std::string& url);
  CLI::Option* DurationOption(double& duration_s);
  // An option whose value is one of `choices`, stored as the matching enumerator.
  template <typename Enum>
  CLI::Option* Choice(const std::string& names, Enum& value,
                      std::vector<std::pair<std::string, Enum>> choices, const std::string& help) {
    std::string listed;
    for (const auto& choice : choices) listed += (listed.empty() ? "" : "|") + choice.first;
    // CLI11 reads an enum as its underlying integer: translate the name to that.
    CLI::Validator to_integer(
        [choices, listed](std::string& input) -> std::string {
          for (const auto& [choice_name, choice] : choices) {
            if (choice_name != input) continue;
            input = std::to_string(static_cast<std::underlying_type_t<Enum>>(choice));
            return "";
          }
          return "'" + input + "' is not one of " + listed;
        },
        "");
    CLI::Option* option = app_.add_option(names, value, help)->transform(to_integer);
    option->type_name(listed)->default_str(NameOf(value, choices));
    Echo(option, [&value, choices] { return NameOf(value, choices); });
    return option;
  }
  // Echoes a value the options do not hold (a value derived from them, or read from a file).
  void EchoValue(const std::string& key, std::function<std::string()> value);
  // Echoes a setting that only the program's file holds, under its key path in that file
  // ("sync.period", "joints[0].node"), from the variable it was read into: echoed with the options,
  // formatted as they are, at LogConfiguration() time (so after the file is read).
  template <typename T>
  void Setting(const std::string& key, const T& value) {
    EchoValue(key, [&value] { return FormatValue(value); });
  }

  // Parses the command line and starts the logger (-v: debug, -q: warnings and errors). First
  // checks that every long option name, also of subcommands and options added through app(), and
  // every subcommand name is kebab-case (abort otherwise: a programmer error).
  // Returns nothing when the program should go on, else the exit code: kExitOk after --help,
  // kExitUsage (or the code a validator's CLI::ParseError carries) after "error: <reason>".
  std::optional<int> Parse(int argc, char** argv);

  // Assigns again every option given on the command line: after reading a configuration file
  // into the variables the options are bound to, so that flags override the file.
  void ApplyCommandLineAgain();

  // "key=value key=value ...", in the order the options were added.
  std::string Configuration() const;
  // Logs "config: " + Configuration() at info level.
  void LogConfiguration() const;

  // Opens the bus at `url` and logs which one; the error names the URL.
  Expected<std::unique_ptr<Bus>> OpenBus(const std::string& url) const;
  Expected<std::unique_ptr<Bus>> OpenBus(const std::string& url, const PublishPacing& pacing) const;

 private:
  struct Echoed {
    std::string key;
    CLI::Option* option = nullptr;  // null for EchoValue entries
    std::function<std::string()> value;
  };

  template <typename Enum>
  static std::string NameOf(Enum value, const std::vector<std::pair<std::string, Enum>>& choices) {
    for (const auto& [name, choice] : choices) {
      if (choice == value) return name;
    }
    return "?";
  }
  void Echo(CLI::Option* option, std::function<std::string()> value);

  std::string name_;
  CLI::App app_;
  bool verbose_ = false;
  bool quiet_ = false;
  std::vector<Echoed> echoed_;
};

// The main() of every program: describes the options into a `Settings`, parses the command line,
// then hands the program and its settings to `start`, whose result is the exit code.
//   constexpr program::About kAbout{"selfcal-foo", "selfcal-foo: what it does"};
//   ...
//   int main(int argc, char** argv) {
//     return program::Main<Settings>(argc, argv, kAbout, DescribeOptions, Start);
//   }
template <typename Settings, typename Describe, typename Start>
int Main(int argc, char** argv, const About& about, Describe describe, Start start) {
  Program program(about);
  Settings settings;
  describe(program, settings);
  if (auto exit = program.Parse(argc, argv)) return *exit;
  return start(program, settings);
}

}  // namespace selfcal::program
