// selfcald's state machine: IDLE -> CHECKING -> MOVING/RECORDING -> CALIBRATING -> VALIDATING ->
// ACCEPTED | REJECTED -> IDLE, and ABORTED and FAILED with a reason. Single-threaded over the bus
// (LCM handlers, motion commands, checks, recording); the calibration runs in a worker thread at
// lower priority and reports progress through atomics.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/util/expected.h"
#include "daemon/auth.h"
#include "daemon/config.h"
#include "daemon/engine.h"
#include "daemon/history.h"
#include "daemon/model_store.h"
#include "daemon/plan.h"
#include "daemon/sessions.h"
#include "protocols/bus/bus.h"
#include "protocols/lcm_log/lcm_log.h"
#include "selfcal/calibration_request_t.hpp"
#include "selfcal/calibration_status_t.hpp"

namespace selfcal::daemon {

using State = std::int8_t;  // selfcal::calibration_status_t::IDLE ...
const char* StateName(State state);
bool IsTerminal(State state);

std::int64_t NowUtime();  // CLOCK_REALTIME [us], as LCM's utime

class Daemon {
 public:
  // Reads the key (refusing a key file others may read), opens the storage, marks interrupted
  // sessions incomplete, reads the plans and subscribes.
  static Expected<std::unique_ptr<Daemon>> Create(const DaemonConfig& config,
                                                  std::shared_ptr<Bus> bus,
                                                  std::unique_ptr<CalibrationEngine> engine,
                                                  UrdfExporter urdf_exporter);
  ~Daemon();

  // Handles messages for up to `wait`, then advances the state machine and publishes status.
  // An error is a broken bus: the caller should exit and let systemd restart the service.
  Status Step(std::chrono::milliseconds wait);

  State state() const { return state_; }
  const std::string& message() const { return message_; }
  const std::vector<std::string>& interrupted_sessions() const { return interrupted_; }

 private:
  struct MotionStep {
    enum Kind { kMove, kSettle, kSweep } kind = kMove;
    Motion motion;
    double duration = 0;
    int scan_index = -1;
    bool validation = false;
  };
  struct Worker {
    std::atomic<bool> stop{false};
    std::atomic<bool> done{false};
    std::atomic<int> phase{0};  // 0 calibrating, 1 validating
    std::atomic<float> progress{0};
    std::mutex mutex;
    std::string stage;  // guarded by mutex
    std::optional<Expected<CalibratedModel>> calibrated;
    double rms_before = -1, rms_after = -1;
    std::string error;  // validation failure
  };

  Daemon(DaemonConfig config, std::shared_ptr<Bus> bus, std::unique_ptr<CalibrationEngine> engine,
         Key key, SessionStore sessions, ModelStore models, std::unique_ptr<History> history);

  void OnRequest(const BusMessage& message);
  void OnJointState(const BusMessage& message);
  void OnSensor(const BusMessage& message);

  void Transition(State state, const std::string& message, float progress = 0);
  void PublishStatus(const std::string& request_nonce = {});
  void Refuse(const selfcal::calibration_request_t& request, const std::string& why);

  void StartSession(const selfcal::calibration_request_t& request, const std::string& plan_name);
  void RunChecks();
  void TickMotion(std::int64_t now);
  void FinishRecording();
  void StartCalibration();
  void TickCalibration();
  void EndSession(State outcome, const std::string& reason);
  void Abort(const std::string& reason);
  void HoldPosition();
  void Record(const BusMessage& message);
  void PublishMarker(std::int8_t event, const MotionStep& step);
  std::vector<double> PlannedAt(double t) const;
  void PersistSession();

  DaemonConfig config_;
  std::shared_ptr<Bus> bus_;
  std::unique_ptr<CalibrationEngine> engine_;
  RequestAuthenticator authenticator_;
  SessionStore sessions_;
  ModelStore models_;
  std::unique_ptr<History> history_;
  std::map<std::string, ScanPlan> plans_;
  std::vector<std::string> joint_names_;
  std::vector<std::string> interrupted_;

  State state_ = 0;
  std::string message_ = "starting";
  float progress_ = 0;
  std::int64_t last_status_utime_ = 0;

  // Inputs.
  std::int64_t joint_receive_utime_ = 0;
  std::vector<double> joint_positions_;
  std::string joint_error_;  // why the last joint state was unusable
  std::int64_t sensor_receive_utime_ = 0;

  // The session.
  SessionMeta session_;
  SessionRecord record_;
  std::optional<ModelFile> session_model_;
  ScanPlan session_plan_;
  std::optional<LcmLogWriter> writer_;
  std::string writer_error_;
  std::vector<MotionStep> steps_;
  std::size_t step_index_ = 0;
  std::int64_t step_start_utime_ = 0;
  std::int64_t next_command_utime_ = 0;
  std::int64_t calibration_start_utime_ = 0;
  std::shared_ptr<Worker> worker_;
  std::thread worker_thread_;
};

}  // namespace selfcal::daemon
