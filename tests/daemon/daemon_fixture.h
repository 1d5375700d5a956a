// The daemon in-process over real LCM (memq://), with the TestArm as arm and sensor and the
// scripted engine, for the daemon's service and security tests. Daemon, arm and engine share a
// ManualClock: the sessions run in simulated time, a few times faster than real time.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <functional>
#include <optional>
#include <thread>

#include "core/util/atomic_file.h"
#include "daemon/daemon.h"
#include "selfcal/calibration_result_t.hpp"
#include "tests/daemon/scripted_engine.h"
#include "tests/daemon/test_arm.h"

namespace selfcal::daemon {

namespace fs = std::filesystem;
using Status_t = selfcal::calibration_status_t;
using Request_t = selfcal::calibration_request_t;

inline std::string SourceDir() {
  const char* dir = std::getenv("SELFCAL_SOURCE_DIR");
  return dir ? dir : ".";
}

// A short plan: two fitted sweeps and one held back, 0.2 rad each.
inline constexpr char kPlan[] = R"(name: tiny
scans:
  - {purpose: fit, from: [0.0, 0.5, 0.0, -1.2, 0.0, 0.8, 0.0], to: [0.2, 0.5, 0.0, -1.2, 0.0, 0.8, 0.0], speed: 0.5}
  - {purpose: fit, from: [0.2, 0.5, 0.0, -1.2, 0.0, 0.8, 0.0], to: [0.2, 0.5, 0.0, -1.2, 0.0, 0.8, 0.2], speed: 0.5}
  - {purpose: validation, from: [0.2, 0.4, 0.0, -1.2, 0.0, 0.8, 0.2], to: [0.2, 0.4, 0.0, -1.2, 0.2, 0.8, 0.2], speed: 0.5}
)";

class DaemonFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("selfcal_daemon_service_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    ASSERT_TRUE(auth::GenerateKeyFile(Path("daemon.key")));
    key_ = auth::ReadKeyFile(Path("daemon.key"), true).value();
    ASSERT_TRUE(WriteFileAtomically(Path("tiny.yaml"), kPlan));
    const std::string config =
        "robot_id: test-arm\n"
        "lcm_url: memq://\n"
        "robot_model: " +
        SourceDir() +
        "/config/robots/kuka_lbr_iiwa_r840.yaml\n"
        "sensor: " +
        SourceDir() +
        "/config/sensors/hokuyo_utm30lx.yaml\n"
        "plans: {tiny: tiny.yaml}\n"
        "default_plan: tiny\n"
        "storage: {folder: storage, quota_mb: 100}\n"
        "key_file: daemon.key\n"
        "request_window_s: 30\n"
        "checks: {joint_state_max_age_s: 0.1, sensor_max_age_s: 0.3, max_deviation: 0.05}\n"
        "motion: {speed_fraction: 1.0, settle_time_s: 0.1}\n"
        "acceptance: {min_improvement: 0.05, max_angle_change_rad: 0.05, max_translation_change_m: "
        "0.05}\n"
        "status_rate_hz: 2\n";
    ASSERT_TRUE(WriteFileAtomically(Path("daemon.yaml"), config));
  }
  void TearDown() override {
    daemon_.reset();
    if (!HasFailure()) fs::remove_all(dir_);
  }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  void Start(const std::string& script = "seconds=0.3") {
    auto config = ReadDaemonConfig(Path("daemon.yaml"));
    ASSERT_TRUE(config) << config.error().message;
    config_ = *config;
    bus_ = std::shared_ptr<Bus>(OpenLcmBus("memq://").value());
    arm_ = std::make_unique<testing::TestArm>(bus_, testing::TestArmOptions{});
    arm_->position = {0.0, 0.5, 0.0, -1.2, 0.0, 0.8, 0.0};
    bus_->Subscribe(config_.channels.calibration_status, [this](const BusMessage& m) {
      statuses_.push_back(DecodeLcm<Status_t>(m.data, m.channel).value());
    });
    bus_->Subscribe(config_.channels.calibration_result, [this](const BusMessage& m) {
      results_.push_back(DecodeLcm<selfcal::calibration_result_t>(m.data, m.channel).value());
    });
    auto engine =
        std::make_unique<testing::ScriptedEngine>(testing::ParseScript(script).value(), clock_);
    auto daemon = Daemon::Create(config_, wrap_daemon_bus_ ? wrap_daemon_bus_(bus_) : bus_,
                                 std::move(engine), {}, clock_);
    ASSERT_TRUE(daemon) << daemon.error().message;
    daemon_ = std::move(daemon).value();
    RunFor(0.3);  // joint states and sensor flowing
  }

  std::int64_t Now() const { return clock_->Now(); }

  // Steps the daemon and the arm until `done` or `seconds` pass; false on timeout. Each step is
  // 2 ms of simulated time and at least 0.1 ms of real time, so that the engine's worker thread
  // keeps up with the clock even when the machine is loaded.
  bool RunUntil(const std::function<bool()>& done, double seconds) {
    const std::int64_t end = clock_->Monotonic() + static_cast<std::int64_t>(seconds * 1e6);
    while (clock_->Monotonic() < end) {
      if (!daemon_->Step(std::chrono::milliseconds(0))) return false;
      clock_->Advance(2000);
      arm_->Tick(clock_->Monotonic());  // the arm's time is its own: steps of ours do not reach it
      if (done()) return true;
      std::this_thread::sleep_for(std::chrono::microseconds(100));
    }
    return false;
  }
  void RunFor(double seconds) {
    RunUntil([] { return false; }, seconds);
  }

  Request_t MakeRequest(std::int8_t action, const auth::Key& key, std::int64_t utime = 0) {
    Request_t request;
    request.utime = utime ? utime : Now();
    request.action = action;
    request.robot_id = "test-arm";
    request.nonce = RandomNonce();
    request.plan_name = "";
    request.requested_by = "daemon_service_test";
    SignRequest(request, key);
    return request;
  }
  // Sends a request and returns the status that answers it.
  Status_t Send(const Request_t& request) {
    results_mark_ = results_.size();
    const std::size_t from = statuses_.size();
    EXPECT_TRUE(bus_->Publish(config_.channels.calibration_request, request));
    std::optional<Status_t> answer;  // a copy: statuses_ grows while we wait
    RunUntil(
        [&] {
          for (std::size_t i = from; i < statuses_.size() && !answer; ++i) {
            if (statuses_[i].request_nonce == request.nonce) answer = statuses_[i];
          }
          return answer.has_value();
        },
        2.0);
    EXPECT_TRUE(answer.has_value()) << "no answer to " << request.nonce;
    return answer.value_or(Status_t{});
  }
  bool ReachState(State state, double seconds) {
    const std::size_t from = statuses_.size();
    return RunUntil(
        [&] {
          for (std::size_t i = from; i < statuses_.size(); ++i) {
            if (StateFromWire(statuses_[i].state) == state) return true;
          }
          return daemon_->state() == state;
        },
        seconds);
  }
  // Waits for the result of the session the last Send() started.
  bool WaitResult(double seconds) {
    return RunUntil([&] { return results_.size() > results_mark_; }, seconds);
  }
  std::string CurrentModelText() {
    return ReadFile(Path("storage/models/current/model.yaml")).value();
  }
  std::string SessionStatus(const std::string& id) {
    return SessionStore(Path("storage")).Read(id).value().status;
  }

  std::shared_ptr<ManualClock> clock_ = std::make_shared<ManualClock>(timing::RealtimeUs());
  fs::path dir_;
  auth::Key key_{};
  DaemonConfig config_;
  std::shared_ptr<Bus> bus_;
  std::unique_ptr<testing::TestArm> arm_;
  std::unique_ptr<Daemon> daemon_;
  // When set, Start gives the daemon this bus around the test's (to make its bus misbehave).
  std::function<std::shared_ptr<Bus>(std::shared_ptr<Bus>)> wrap_daemon_bus_;
  std::vector<Status_t> statuses_;
  std::vector<selfcal::calibration_result_t> results_;
  std::size_t results_mark_ = 0;
};

}  // namespace selfcal::daemon
