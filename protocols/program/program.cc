#include "protocols/program/program.h"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <iostream>

namespace selfcal::program {
namespace {

std::atomic<bool> g_stop{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the stop flag is set from a signal handler");

void OnStopSignal(int /*signal*/) { g_stop.store(true); }

spdlog::level::level_enum ToSpdlog(LogLevel level) {
  switch (level) {
    case LogLevel::kDebug:
      return spdlog::level::debug;
    case LogLevel::kInfo:
      return spdlog::level::info;
    case LogLevel::kWarning:
      return spdlog::level::warn;
    case LogLevel::kError:
      return spdlog::level::err;
  }
  return spdlog::level::err;
}

// A long option name must be kebab-case: --lcm-url, never --lcm_url or --LcmUrl.
bool IsKebabCase(const std::string& name) {
  if (name.empty() || name.front() == '-' || name.back() == '-') return false;
  for (const char c : name) {
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-')) return false;
  }
  return true;
}

// Aborts (a programmer error, caught by any run of the program) when a long name of `option`
// is not kebab-case; `where` names the command that holds it.
void RequireKebabCase(const std::string& where, const CLI::Option& option) {
  for (const std::string& long_name : option.get_lnames()) {
    if (!IsKebabCase(long_name)) {
      std::cerr << where << ": option --" << long_name << " is not kebab-case\n";
      std::abort();
    }
  }
}

// The same for every option of `app` and, recursively, of its subcommands and their names.
void RequireKebabCase(const std::string& where, const CLI::App& app) {
  for (const CLI::Option* option : app.get_options()) RequireKebabCase(where, *option);
  for (const CLI::App* command : app.get_subcommands({})) {
    const std::string name = where + " " + command->get_name();
    if (!IsKebabCase(command->get_name())) {
      std::cerr << name << ": command name is not kebab-case\n";
      std::abort();
    }
    RequireKebabCase(name, *command);
  }
}

}  // namespace

const CLI::Validator kPositive(
    [](const std::string& input) -> std::string {
      double value = 0;
      if (!CLI::detail::lexical_cast(input, value)) return "'" + input + "' is not a number";
      return value > 0 ? "" : "must be positive, not " + input;
    },
    "POSITIVE");

const CLI::Validator kNonNegative(
    [](const std::string& input) -> std::string {
      double value = 0;
      if (!CLI::detail::lexical_cast(input, value)) return "'" + input + "' is not a number";
      return value >= 0 ? "" : "must not be negative, not " + input;
    },
    "NONNEGATIVE");

std::string InstalledConfig(const std::string& relative) {
  return std::string(SELFCAL_CONFIG_DIR) + "/" + relative;
}

int Fail(std::string_view reason, int exit_code) {
  std::cerr << "error: " << reason << "\n";
  return exit_code;
}

int ExitCode(const Status& status) { return status.ok() ? kExitOk : Fail(status.error().message); }

std::atomic<bool>& StopFlag() { return g_stop; }

std::atomic<bool>& StopOnSignals() {
  std::signal(SIGINT, OnStopSignal);
  std::signal(SIGTERM, OnStopSignal);
  return g_stop;
}

int RunUntilStopped(double duration_s, const std::function<Status()>& step) {
  const std::atomic<bool>& stop = StopOnSignals();
  const auto start = std::chrono::steady_clock::now();
  const auto limit = std::chrono::duration<double>(duration_s);
  while (!stop.load()) {
    if (auto status = step(); !status.ok()) return ExitCode(status);
    if (duration_s > 0 && std::chrono::steady_clock::now() - start > limit) break;
  }
  return kExitOk;
}

void Log(LogLevel level, const std::string& message) {
  spdlog::log(ToSpdlog(level), "{}", message);
}

LogSink Logger() {
  return [](LogLevel level, const std::string& message) { Log(level, message); };
}

Program::Program(std::string name, const std::string& description)
    : name_(std::move(name)), app_(description, name_) {
  app_.add_flag("-v,--verbose", verbose_, "Log debug messages");
  app_.add_flag("-q,--quiet", quiet_, "Log warnings and errors only");
  // Logs go to stderr so that stdout carries only results; set up before parsing so that
  // validators and subcommand callbacks may log.
  if (auto existing = spdlog::get(name_)) {
    spdlog::set_default_logger(existing);
  } else {
    spdlog::set_default_logger(spdlog::stderr_color_mt(name_));
  }
  // systemd's journal adds its own timestamps.
  if (std::getenv("JOURNAL_STREAM") != nullptr) spdlog::set_pattern("[%l] %v");
  app_.parse_complete_callback([this] {
    spdlog::set_level(verbose_ ? spdlog::level::debug
                               : (quiet_ ? spdlog::level::warn : spdlog::level::info));
  });
}

CLI::Option* Program::Flag(const std::string& names, bool& value, const std::string& help) {
  CLI::Option* option = app_.add_flag(names, value, help);
  Echo(option, [&value] { return FormatValue(value); });
  return option;
}

CLI::Option* Program::LcmUrlOption(std::string& url) {
  return Option("--lcm-url", url, "LCM URL (empty: LCM_DEFAULT_URL or liblcm's default)");
}

CLI::Option* Program::DurationOption(double& duration_s) {
  return Option("--duration", duration_s, "Exit after this many seconds (0: until SIGINT)");
}

void Program::Echo(CLI::Option* option, std::function<std::string()> value) {
  RequireKebabCase(name_, *option);  // at once, so the message points at the definition
  // Echo keys are the configuration files' spelling: --line-time-us is line_time_us.
  std::string key = option->get_single_name();
  std::replace(key.begin(), key.end(), '-', '_');
  echoed_.push_back({std::move(key), option, std::move(value)});
}

void Program::EchoValue(const std::string& key, std::function<std::string()> value) {
  echoed_.push_back({key, nullptr, std::move(value)});
}

std::optional<int> Program::Parse(int argc, char** argv) {
  // Options added through app() directly, and subcommands' (the selfcal command line's).
  RequireKebabCase(name_, app_);
  try {
    app_.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help, --help-all and --version end here with exit code 0.
    if (e.get_exit_code() == 0) return app_.exit(e);
    // CLI11's own errors carry codes from 100 up; a validator may throw its own code.
    return Fail(e.what(), e.get_exit_code() >= 100 ? kExitUsage : e.get_exit_code());
  }
  return std::nullopt;
}

void Program::ApplyCommandLineAgain() {
  for (const Echoed& echoed : echoed_) {
    if (echoed.option != nullptr && echoed.option->count() > 0) echoed.option->run_callback();
  }
}

std::string Program::Configuration() const {
  std::string text;
  for (const Echoed& echoed : echoed_) {
    if (!text.empty()) text += ' ';
    text += echoed.key + "=" + echoed.value();
  }
  return text;
}

void Program::LogConfiguration() const { spdlog::info("config: {}", Configuration()); }

Expected<std::unique_ptr<Bus>> Program::OpenBus(const std::string& url) const {
  return OpenBus(url, PublishPacing{});
}

Expected<std::unique_ptr<Bus>> Program::OpenBus(const std::string& url,
                                                const PublishPacing& pacing) const {
  auto bus = OpenLcmBus(url, pacing);
  if (bus) spdlog::debug("bus: {}", (*bus)->url());
  return bus;
}

}  // namespace selfcal::program
