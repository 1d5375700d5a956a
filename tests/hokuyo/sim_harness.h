// The real driver against the simulator, in one process: the simulator on its own thread
// (TCP on 127.0.0.1 port 0, or a pty behind a stable link), the driver on another, every
// published scan and every truth the simulator reports kept for the test to compare.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "drivers/hokuyo/driver.h"
#include "tools/sim_scip/sim_server.h"

namespace selfcal::hokuyo::testing {

enum class Link { kTcp, kPty };
inline std::string LinkName(Link link) { return link == Link::kTcp ? "Tcp" : "Pty"; }

class SimHarness {
 public:
  // `short_backoff`: reconnect within 0.4 s (most tests); false keeps the config's backoff.
  SimHarness(Link link, sim_scip::SimDeviceConfig device, HokuyoConfig config = {},
             bool short_backoff = true) {
    sim_scip::SimServerOptions options;
    if (link == Link::kPty) {
      options.transport = sim_scip::SimServerOptions::Transport::kPty;
      options.pty_link =
          "/tmp/selfcal-hokuyo-test-" + std::to_string(getpid()) + "-" + std::to_string(counter_++);
    }
    auto sim = sim_scip::SimServer::Start(device, options);
    if (!sim) {
      ADD_FAILURE() << sim.error().message;
      return;
    }
    sim_ = std::move(*sim);
    sim_->SetTruthCallback([this](const sim_scip::ScanTruth& truth) {
      std::lock_guard<std::mutex> lock(mutex_);
      truths_[truth.timing.timestamp_ms] = truth;
    });
    if (link == Link::kTcp) {
      config.host = "127.0.0.1";
      config.port = sim_->port();
    } else {
      config.device = sim_->pty_path();
    }
    if (short_backoff) {
      config.backoff_initial_s = 0.05;
      config.backoff_max_s = 0.4;
    }
    // Generous: a loaded test machine can starve a thread for a few hundred ms.
    config.stall_timeout_s = 1.0;
    config.reply_timeout_s = 1.0;
    config_ = config;
    driver_ = std::make_unique<HokuyoDriver>(
        config,
        [this](const RangeScan& scan) {
          std::lock_guard<std::mutex> lock(mutex_);
          scans_.push_back(scan);
        },
        [this](LogLevel level, const std::string& message) {
          std::lock_guard<std::mutex> lock(mutex_);
          if (level != LogLevel::kDebug) logs_.push_back(message);
        });
    driver_->SetInfoCallback([this](const SensorInfo& info) {
      std::lock_guard<std::mutex> lock(mutex_);
      infos_.push_back(info);
    });
    thread_ = std::thread([this] { driver_->Run(stop_); });
  }

  ~SimHarness() { Stop(); }

  void Stop() {
    stop_.store(true);
    if (thread_.joinable()) thread_.join();
    if (sim_) sim_->Stop();
  }

  // Waits until `count` scans were published (true) or `timeout_s` passed (false).
  bool WaitForScans(std::size_t count, double timeout_s) {
    const auto until = std::chrono::steady_clock::now() +
                       std::chrono::microseconds(static_cast<std::int64_t>(timeout_s * 1e6));
    while (std::chrono::steady_clock::now() < until) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (scans_.size() >= count) return true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
  }

  std::size_t ScanCount() {
    std::lock_guard<std::mutex> lock(mutex_);
    return scans_.size();
  }
  std::vector<RangeScan> Scans() {
    std::lock_guard<std::mutex> lock(mutex_);
    return scans_;
  }
  std::vector<SensorInfo> Infos() {
    std::lock_guard<std::mutex> lock(mutex_);
    return infos_;
  }
  std::vector<std::string> Logs() {
    std::lock_guard<std::mutex> lock(mutex_);
    return logs_;
  }
  bool Truth(std::uint32_t timestamp_ms, sim_scip::ScanTruth& truth) {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = truths_.find(timestamp_ms);
    if (it == truths_.end()) return false;
    truth = it->second;
    return true;
  }
  bool LogsMention(const std::string& text) {
    for (const auto& line : Logs()) {
      if (line.find(text) != std::string::npos) return true;
    }
    return false;
  }

  sim_scip::SimServer& sim() { return *sim_; }
  HokuyoDriver& driver() { return *driver_; }
  const HokuyoConfig& config() const { return config_; }

 private:
  static inline int counter_ = 0;
  std::unique_ptr<sim_scip::SimServer> sim_;
  HokuyoConfig config_;
  std::unique_ptr<HokuyoDriver> driver_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
  std::mutex mutex_;
  std::vector<RangeScan> scans_;
  std::vector<SensorInfo> infos_;
  std::vector<std::string> logs_;
  std::map<std::uint32_t, sim_scip::ScanTruth> truths_;
};

}  // namespace selfcal::hokuyo::testing
