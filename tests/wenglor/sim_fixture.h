// Test fixture around the fake libEthernetScanner.so (tools/sim_wenglor): a private control file
// and call log per test, and helpers to inject faults and read what the library saw.
#pragma once

#include <gtest/gtest.h>
#include <stdlib.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "drivers/wenglor/wenglor_scanner.h"

namespace selfcal::wenglor::testing {

class SimWenglorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() /
           ("selfcal_wenglor_" + std::to_string(getpid()) + "_" + info->test_suite_name() + "_" +
            info->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    control_path_ = (dir_ / "control").string();
    log_path_ = (dir_ / "calls.log").string();
    setenv("SELFCAL_SIM_WENGLOR_CONTROL", control_path_.c_str(), 1);
    setenv("SELFCAL_SIM_WENGLOR_LOG", log_path_.c_str(), 1);
    // Every test starts from the same simulated sensor, whatever an earlier test set.
    Control("set scene objects");
    Control("set columns 1280");
    Control("set noise_mm 0.2");
    Control("set connect_delay_ms 20");
    Control("set fifo_profiles 2000");
    Control("set counter_start 0");
    Control("set encoder_rate_hz 10000");
    Control("set speed 0.2");
    Control("set height 0.8");
    Control("set seed 1");
  }
  void TearDown() override {
    unsetenv("SELFCAL_SIM_WENGLOR_CONTROL");
    unsetenv("SELFCAL_SIM_WENGLOR_LOG");
    std::filesystem::remove_all(dir_);
  }

  // Appends "<id> <line>" to the control file (rewritten and renamed, so readers see it whole).
  void Control(const std::string& line) {
    control_ += std::to_string(++control_id_) + " " + line + "\n";
    const std::string partial = control_path_ + ".partial";
    {
      std::ofstream file(partial, std::ios::trunc);
      file << control_;
    }
    std::filesystem::rename(partial, control_path_);
  }

  // The calls the library logged, one per line.
  std::vector<std::string> Calls() const {
    std::vector<std::string> lines;
    std::ifstream file(log_path_);
    std::string line;
    while (std::getline(file, line)) lines.push_back(line);
    return lines;
  }
  // Calls that are part of the connection sequence (no control echoes, no start line details).
  std::vector<std::string> ApiCalls() const {
    std::vector<std::string> lines;
    for (const auto& line : Calls()) {
      if (line.rfind("control", 0) == 0 || line.rfind("start ", 0) == 0 ||
          line.rfind("link dropped", 0) == 0) {
        continue;
      }
      lines.push_back(line);
    }
    return lines;
  }
  void ClearLog() { std::filesystem::remove(log_path_); }

  // The realtime [us] at which the fake started its last acquisition.
  std::int64_t LastStartUtime() const {
    std::int64_t utime = -1;
    for (const auto& line : Calls()) {
      if (line.rfind("start realtime_us=", 0) == 0) {
        utime = std::stoll(line.substr(std::string("start realtime_us=").size()));
      }
    }
    return utime;
  }

  WenglorConfig Config() const {
    WenglorConfig config;
    config.library_path = SELFCAL_SIM_WENGLOR_LIBRARY;
    config.ip = "127.0.0.1";
    config.line_time_us = 1000;  // 1 kHz: tests run quickly
    config.connect_timeout_ms = 500;
    config.data_timeout_ms = 300;
    config.reconnect_interval_ms = 20;
    config.poll_interval_us = 100;
    return config;
  }

  std::unique_ptr<WenglorScanner> MakeScanner(const WenglorConfig& config) {
    auto scanner = WenglorScanner::Create(
        config, [this](LogLevel, const std::string& message) { log_messages_.push_back(message); });
    EXPECT_TRUE(scanner.ok()) << (scanner.ok() ? "" : scanner.error().message);
    if (!scanner.ok()) return nullptr;
    return std::move(*scanner);
  }

  // Polls until `count` profiles arrived (each handed to `each`) or `timeout` passes.
  // Returns every result seen, in order.
  template <typename Each>
  std::vector<PollResult> PollProfiles(
      WenglorScanner& scanner, int count, Each each,
      std::chrono::milliseconds timeout = std::chrono::seconds(5)) {
    std::vector<PollResult> results;
    Profile profile;
    int received = 0;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (received < count && std::chrono::steady_clock::now() < deadline) {
      const PollResult result = scanner.Poll(profile);
      results.push_back(result);
      if (result == PollResult::kProfile) {
        ++received;
        each(profile);
      } else if (result == PollResult::kLinkLost) {
        break;
      } else if (result == PollResult::kNoNewScan) {
        std::this_thread::sleep_for(std::chrono::microseconds(100));
      }
    }
    return results;
  }

  // Polls until the scanner reports a lost link, or `timeout`.
  bool WaitLinkLost(WenglorScanner& scanner, std::chrono::milliseconds timeout) {
    Profile profile;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      if (scanner.Poll(profile) == PollResult::kLinkLost) return true;
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    return false;
  }

  std::filesystem::path dir_;
  std::string control_path_;
  std::string log_path_;
  std::string control_;
  int control_id_ = 0;
  std::vector<std::string> log_messages_;
};

inline bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace selfcal::wenglor::testing
