// selfcald's state machine (daemon/state.h), single-threaded over the bus: requests go through
// the request policy, the motion executor moves the arm through the plan while the recorder
// writes the session's log, the engine runner calibrates in a worker thread, the acceptance gate
// decides, and every session ends with one result message.
#pragma once

#include <chrono>
#include <cstdint>
#include <future>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/util/expected.h"
#include "core/util/log.h"
#include "daemon/auth.h"
#include "daemon/clock.h"
#include "daemon/config.h"
#include "daemon/engine.h"
#include "daemon/engine_runner.h"
#include "daemon/history.h"
#include "daemon/model_store.h"
#include "daemon/motion_executor.h"
#include "daemon/plan.h"
#include "daemon/recorder.h"
#include "daemon/request_policy.h"
#include "daemon/sessions.h"
#include "daemon/state.h"
#include "protocols/bus/bus.h"
#include "protocols/model_file/model_file.h"
#include "selfcal/calibration_request_t.hpp"
#include "selfcal/calibration_status_t.hpp"

namespace selfcal::daemon {

class Daemon {
 public:
  // Reads the key (refusing a key file others may read), opens the storage, marks interrupted
  // sessions incomplete, reads the plans and subscribes. Time comes from `clock` (the system's
  // when null).
  static Expected<std::unique_ptr<Daemon>> Create(const DaemonConfig& config,
                                                  std::shared_ptr<Bus> bus,
                                                  std::unique_ptr<CalibrationEngine> engine,
                                                  UrdfExporter urdf_exporter,
                                                  std::shared_ptr<const Clock> clock = nullptr);

  // Handles messages for up to `wait` (less when a scan boundary is due sooner), then advances
  // the state machine and publishes status. An error is a broken bus: the caller should exit and
  // let systemd restart the service.
  Status Step(std::chrono::milliseconds wait);

  State state() const { return state_; }
  const std::string& message() const { return message_; }

 private:
  // The last usable joint state and sensor message, received when the daemon's monotonic clock
  // said so [us].
  struct Inputs {
    std::int64_t joint_time = 0;  // 0 = none yet
    std::vector<double> joint_positions;
    std::string joint_error;  // why the last joint state was unusable
    std::int64_t sensor_time = 0;
    // The arm's driver (robot_driver_status_t): FRI session state and command source.
    std::int64_t driver_time = 0;  // 0 = none yet
    int driver_session_state = -1;
    int driver_source = 0;
  };
  // An authentic request waiting for its batch (HandleRequests).
  struct PendingRequest {
    selfcal::calibration_request_t request;
    std::int64_t received_utime;  // [us, wall time]
  };

  Daemon(DaemonConfig config, std::shared_ptr<Bus> bus, std::unique_ptr<CalibrationEngine> engine,
         auth::Key key, SessionStore sessions, ModelStore models, std::unique_ptr<History> history,
         std::shared_ptr<const Clock> clock);
  Status Load();  // current model, plans, interrupted sessions, used nonces
  void MarkInterrupted(const std::vector<std::string>& ids, std::int64_t now);
  void Subscribe();

  // Authenticates a request; an authentic one waits in pending_ for HandleRequests.
  void OnRequest(const BusMessage& message);
  void HandleRequests();
  std::size_t DecideChunk(const std::vector<PendingRequest>& batch, std::size_t begin,
                          std::vector<RequestDecision>& decisions,
                          std::vector<RequestRow>& rows) const;
  void AnswerRequest(const selfcal::calibration_request_t& request, RequestDecision& decision,
                     const Status& logged, std::int64_t time);
  void OnJointState(const BusMessage& message);
  void OnSensor(const BusMessage& message);
  void OnDriverStatus(const BusMessage& message);
  void Act(const selfcal::calibration_request_t& request, const RequestDecision& decision);

  void Transition(State state, const std::string& message, float progress = 0);
  selfcal::calibration_status_t MakeStatus() const;
  void PublishStatus(const std::string& request_nonce = {});
  void Refuse(const selfcal::calibration_request_t& request, const std::string& why);
  void CountRefusal(const std::string& reason, const std::string& details, std::int64_t time);

  void StartSession(const selfcal::calibration_request_t& request, const std::string& plan_name);
  void RunChecks();
  std::optional<std::string> InputProblem(std::int64_t now) const;
  std::string DriverProblem(std::int64_t now) const;
  Status PrepareStorage();
  void StartMotion();
  void TickMotion();
  void OnMotionEvent(const MotionEvent& event);
  void PublishMarker(std::int8_t event, const ScanTiming& scan);
  void FinishRecording();
  void StartCalibration();
  void TickCalibration();
  void Conclude(const CalibratedModel& calibrated);
  void AddRemasterCorrections();
  void Install(const std::string& gate_reason);
  void EndSession(State outcome, const std::string& reason);
  void PublishResult(State outcome, const std::string& reason, std::int64_t now);
  void Abort(const std::string& reason);
  bool PersistSession();
  void RetryUnsavedEnds(std::int64_t now);

  DaemonConfig config_;
  std::shared_ptr<Bus> bus_;
  std::shared_ptr<const Clock> clock_;
  std::unique_ptr<CalibrationEngine> engine_;
  RequestAuthenticator authenticator_;
  SessionStore sessions_;
  ModelStore models_;
  std::unique_ptr<History> history_;
  std::map<std::string, ScanPlan> plans_;
  std::vector<std::string> joint_names_;
  MotionExecutor motion_;
  Recorder recorder_;
  EngineRunner runner_;
  // Authentic requests received in this turn of the bus, decided and stored together.
  std::vector<PendingRequest> pending_;
  // Refused requests (forged or authentic): the first of each reason per interval is logged, the
  // rest counted.
  RateLimitedLog refusals_;
  RateLimit answers_;  // answers to those
  bool trim_memory_ = false;
  std::int64_t last_trim_time_ = 0;

  State state_ = State::kIdle;
  std::string message_ = "starting";
  float progress_ = 0;
  std::int64_t last_status_time_ = 0;  // monotonic, as every *_time_ here
  std::string last_session_id_;        // the session that ended last, for clients that missed it
  State last_session_state_ = State::kIdle;
  Inputs inputs_;

  // The session.
  SessionMeta session_;
  std::int64_t session_start_time_ = 0;
  SessionRecord record_;
  std::optional<ModelFile> session_model_;
  // What the engine starts from and may change: the session's model, with RemasterMask for a
  // remaster plan (daemon/remaster.h). The gate, the result message and the report judge
  // against it; the installed model keeps the model file's mask.
  std::optional<RobotModel> engine_start_;
  ScanPlan session_plan_;
  std::optional<CalibratedModel> calibrated_;

  // Ended sessions whose end could not be written (a full disk): retried every second, so that
  // the history and session.yaml do not say "recording" once there is room again.
  struct UnsavedEnd {
    SessionMeta meta;
    SessionRecord record;
    bool has_folder = false;
  };
  std::vector<UnsavedEnd> unsaved_ends_;
  std::int64_t last_save_retry_time_ = 0;

  // The last session's report (daemon/session_report.h), written beside the loop: seconds of
  // work that would otherwise stop the status. Last, so that it is waited for first.
  std::future<void> report_;
};

}  // namespace selfcal::daemon
