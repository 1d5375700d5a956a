// Helpers for the camera integration tests: child processes and an LCM listener.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "protocols/bus/bus.h"
#include "protocols/lcm_log/lcm_codec.h"
#include "tests/time_scale.h"

extern char** environ;

namespace selfcal::testing {

// A child process, stopped with SIGTERM when the handle goes away; stderr goes to a file.
class Child {
 public:
  Child(const std::vector<std::string>& args, const std::string& stderr_path)
      : stderr_path_(stderr_path) {
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 2, stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     0644);
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
    if (posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&actions);
  }
  ~Child() { Stop(); }
  pid_t pid() const { return pid_; }
  bool running() const { return pid_ > 0 && ::kill(pid_, 0) == 0; }
  bool exited() {
    int status = 0;
    if (pid_ > 0 && ::waitpid(pid_, &status, WNOHANG) == pid_) {
      exit_status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      pid_ = -1;
    }
    return pid_ < 0;
  }
  // SIGTERM, then wait; returns the exit status.
  int Stop() {
    if (pid_ > 0) {
      ::kill(pid_, SIGTERM);
      int status = 0;
      ::waitpid(pid_, &status, 0);
      exit_status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      pid_ = -1;
    }
    return exit_status_;
  }
  std::string Stderr() const {
    std::ifstream in(stderr_path_);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }
  // Waits until stderr contains `text`.
  bool WaitForLog(const std::string& text, std::chrono::milliseconds timeout) const {
    const auto end = std::chrono::steady_clock::now() + Scaled(timeout);
    while (std::chrono::steady_clock::now() < end) {
      if (Stderr().find(text) != std::string::npos) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return false;
  }
  // The integer after "key=" in the last line of stderr that has it.
  long long Counter(const std::string& key) const {
    const std::string text = Stderr();
    const auto at = text.rfind(" " + key + "=");
    return at == std::string::npos ? -1 : std::stoll(text.substr(at + key.size() + 2));
  }

 private:
  pid_t pid_ = -1;
  int exit_status_ = -1;
  std::string stderr_path_;
};

// Collects decoded messages of one type from a channel.
template <typename Message>
class Listener {
 public:
  Listener(Bus& bus, const std::string& channel) : bus_(bus) {
    bus.Subscribe(channel, [this](const BusMessage& m) {
      auto decoded = DecodeLcm<Message>(m.data, m.channel);
      if (decoded)
        messages.push_back(std::move(*decoded));
      else
        errors.push_back(decoded.error().message);
    });
  }
  // Handles messages for `duration`.
  void Spin(std::chrono::milliseconds duration) {
    const auto end = std::chrono::steady_clock::now() + duration;
    while (std::chrono::steady_clock::now() < end) {
      auto handled = bus_.HandleOnce(std::chrono::milliseconds(10));
      (void)handled;
    }
  }
  // Handles messages until `count` arrived or `timeout` passed. Returns whether they arrived.
  bool WaitFor(std::size_t count, std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + Scaled(timeout);
    while (messages.size() < count && std::chrono::steady_clock::now() < end) {
      auto handled = bus_.HandleOnce(std::chrono::milliseconds(10));
      (void)handled;
    }
    return messages.size() >= count;
  }
  std::vector<Message> messages;
  std::vector<std::string> errors;

 private:
  Bus& bus_;
};

inline std::int64_t NowUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

inline std::string TempPath(const std::string& name) {
  const char* dir = std::getenv("TMPDIR");
  return std::string(dir ? dir : "/tmp") + "/selfcal-" + std::to_string(::getpid()) + "-" + name;
}

}  // namespace selfcal::testing
