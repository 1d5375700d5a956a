#include "daemon/daemon.h"

#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <limits>
#include <sstream>

#include "daemon/gate.h"
#include "drake/lcmt_iiwa_command.hpp"
#include "protocols/model_file/sensor_config.h"
#include "selfcal/calibration_result_t.hpp"
#include "selfcal/joint_state_t.hpp"
#include "selfcal/scan_marker_t.hpp"

namespace selfcal::daemon {
namespace {

using Status_t = selfcal::calibration_status_t;
// How long CHECKING waits for joint states and sensor data to become fresh [us].
constexpr std::int64_t kInputGrace = 2'000'000;
using Request_t = selfcal::calibration_request_t;

std::string Millis(std::int64_t us) {
  std::ostringstream out;
  out.precision(3);
  out << static_cast<double>(us) / 1000.0 << " ms";
  return out.str();
}

const char* ActionName(std::int8_t action) {
  switch (action) {
    case Request_t::START:
      return "START";
    case Request_t::ABORT:
      return "ABORT";
    case Request_t::ROLLBACK:
      return "ROLLBACK";
  }
  return "UNKNOWN";
}

}  // namespace

const char* StateName(State state) {
  switch (state) {
    case Status_t::IDLE:
      return "IDLE";
    case Status_t::CHECKING:
      return "CHECKING";
    case Status_t::MOVING:
      return "MOVING";
    case Status_t::RECORDING:
      return "RECORDING";
    case Status_t::CALIBRATING:
      return "CALIBRATING";
    case Status_t::VALIDATING:
      return "VALIDATING";
    case Status_t::ACCEPTED:
      return "ACCEPTED";
    case Status_t::REJECTED:
      return "REJECTED";
    case Status_t::ABORTED:
      return "ABORTED";
    case Status_t::FAILED:
      return "FAILED";
  }
  return "UNKNOWN";
}

bool IsTerminal(State state) {
  return state == Status_t::ACCEPTED || state == Status_t::REJECTED || state == Status_t::ABORTED ||
         state == Status_t::FAILED;
}

std::int64_t NowUtime() {
  timespec now{};
  clock_gettime(CLOCK_REALTIME, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1000000 + now.tv_nsec / 1000;
}

Expected<std::unique_ptr<Daemon>> Daemon::Create(const DaemonConfig& config,
                                                 std::shared_ptr<Bus> bus,
                                                 std::unique_ptr<CalibrationEngine> engine,
                                                 UrdfExporter urdf_exporter) {
  auto key = ReadKeyFile(config.key_file, /*require_private=*/true);
  if (!key) return Error{"refusing to start: " + key.error().message};
  std::error_code fs_error;
  std::filesystem::create_directories(config.storage.folder, fs_error);
  if (fs_error)
    return Error{config.storage.folder +
                 ": cannot create the storage folder: " + fs_error.message()};
  auto sensor = ReadSensorConfig(config.sensor);
  if (!sensor) return sensor.error();
  auto models =
      ModelStore::Open(config.storage.folder, config.robot_model, std::move(urdf_exporter));
  if (!models) return models.error();
  auto history = History::Open(config.storage.folder + "/history.sqlite", false);
  if (!history) return history.error();
  std::unique_ptr<Daemon> daemon(new Daemon(config, std::move(bus), std::move(engine), *key,
                                            SessionStore(config.storage.folder),
                                            std::move(models).value(), std::move(history).value()));
  auto current = daemon->models_.Current();
  if (!current) return current.error();
  for (const auto& joint : current->model.joints) daemon->joint_names_.push_back(joint.name);
  for (const auto& [name, path] : config.plans) {
    auto plan = ReadScanPlan(path);
    if (!plan) return plan.error();
    const std::string problem = CheckPlan(*plan, current->model, config.checks.limit_margin);
    if (!problem.empty()) return Error{path + ": " + problem};
    daemon->plans_[name] = std::move(plan).value();
  }
  // A crash (kill -9, power loss) may have left sessions half done: say so, on disk and in the
  // history.
  const std::int64_t now = NowUtime();
  auto interrupted = daemon->sessions_.MarkInterrupted(now);
  if (!interrupted) return interrupted.error();
  for (const auto& id : *interrupted) {
    auto meta = daemon->sessions_.Read(id);
    SessionRecord record;
    record.id = id;
    if (meta) {
      record.started_utime = meta->started_utime;
      record.plan = meta->plan;
      record.requested_by = meta->requested_by;
      record.nonce = meta->nonce;
      record.reason = meta->reason;
    }
    record.ended_utime = now;
    record.state = "incomplete";
    if (auto status = daemon->history_->UpsertSession(record); !status)
      spdlog::warn("{}", status.error().message);
    spdlog::warn("session {} was interrupted; marked incomplete", id);
  }
  daemon->interrupted_ = std::move(interrupted).value();
  // Nonces used before a restart stay used.
  auto nonces = daemon->history_->NoncesSince(now - 2 * daemon->authenticator_.window_us());
  if (nonces) {
    for (const auto& [nonce, utime] : *nonces) daemon->authenticator_.RememberNonce(nonce, utime);
  }
  Daemon* self = daemon.get();
  self->bus_->Subscribe(config.channels.calibration_request,
                        [self](const BusMessage& m) { self->OnRequest(m); });
  self->bus_->Subscribe(config.channels.joint_state,
                        [self](const BusMessage& m) { self->OnJointState(m); });
  self->bus_->Subscribe(config.channels.sensor, [self](const BusMessage& m) { self->OnSensor(m); });
  self->Transition(Status_t::IDLE, "ready; current model " + self->models_.CurrentId());
  return daemon;
}

Daemon::Daemon(DaemonConfig config, std::shared_ptr<Bus> bus,
               std::unique_ptr<CalibrationEngine> engine, Key key, SessionStore sessions,
               ModelStore models, std::unique_ptr<History> history)
    : config_(std::move(config)),
      bus_(std::move(bus)),
      engine_(std::move(engine)),
      authenticator_(key, config_.request_window),
      sessions_(std::move(sessions)),
      models_(std::move(models)),
      history_(std::move(history)) {}

Daemon::~Daemon() {
  if (worker_) worker_->stop = true;
  if (worker_thread_.joinable()) worker_thread_.join();
}

// --- Status -------------------------------------------------------------------------------------

void Daemon::Transition(State state, const std::string& message, float progress) {
  if (state != state_) {
    spdlog::info("{} {}{}", StateName(state), session_.id.empty() ? "" : session_.id + ": ",
                 message);
  } else if (message != message_) {
    spdlog::debug("{} {}{}", StateName(state), session_.id.empty() ? "" : session_.id + ": ",
                  message);
  }
  state_ = state;
  message_ = message;
  progress_ = progress;
  PublishStatus();
}

void Daemon::PublishStatus(const std::string& request_nonce) {
  Status_t status;
  status.utime = NowUtime();
  status.state = state_;
  status.session_id = state_ == Status_t::IDLE ? "" : session_.id;
  status.request_nonce = request_nonce;
  status.progress = progress_;
  status.message = message_;
  if (auto published = bus_->Publish(config_.channels.calibration_status, status); !published) {
    spdlog::warn("{}", published.error().message);
  }
  last_status_utime_ = status.utime;
}

void Daemon::Refuse(const Request_t& request, const std::string& why) {
  // The refusal answers the request without changing the state: a status naming its nonce.
  const std::string saved = message_;
  message_ = why;
  PublishStatus(request.nonce);
  message_ = saved;
}

// --- Inputs -------------------------------------------------------------------------------------

void Daemon::OnRequest(const BusMessage& message) {
  const std::int64_t now = NowUtime();
  auto request = DecodeLcm<Request_t>(message.data, config_.channels.calibration_request);
  if (!request) {
    spdlog::warn("refused a request that does not decode: {}", request.error().message);
    Request_t empty;
    Refuse(empty, "refused: malformed request (" + request.error().message + ")");
    return;
  }
  const Verdict verdict = authenticator_.Check(*request, now);
  const bool authentic = verdict == Verdict::kAccepted;
  std::string outcome = VerdictText(verdict);
  if (authentic) {
    if (request->action == Request_t::ABORT) {
      if (state_ == Status_t::IDLE) outcome = "refused: nothing to abort (idle)";
    } else if (state_ != Status_t::IDLE || (worker_ && !worker_->done)) {
      outcome = std::string("refused: busy (") + StateName(state_) +
                (session_.id.empty() || state_ == Status_t::IDLE ? "" : " session " + session_.id) +
                (state_ == Status_t::IDLE ? ", previous computation still stopping" : "") + ")";
    } else if (request->action == Request_t::START) {
      const std::string plan =
          request->plan_name.empty() ? config_.default_plan : request->plan_name;
      if (!plans_.count(plan)) outcome = "refused: unknown plan '" + plan + "'";
    }
  }
  const std::string log_line = fmt::format(
      "request {} nonce={} by='{}' plan='{}' utime={}: {}", ActionName(request->action),
      request->nonce, request->requested_by, request->plan_name, request->utime, outcome);
  if (outcome == "accepted")
    spdlog::info("{}", log_line);
  else
    spdlog::warn("{}", log_line);
  if (auto logged = history_->LogRequest(now, request->utime, request->nonce, request->action,
                                         request->requested_by, outcome, authentic);
      !logged) {
    spdlog::warn("{}", logged.error().message);
  }
  if (outcome != "accepted") {
    Refuse(*request, outcome);
    return;
  }
  switch (request->action) {
    case Request_t::START: {
      const std::string plan =
          request->plan_name.empty() ? config_.default_plan : request->plan_name;
      StartSession(*request, plan);
      PublishStatus(request->nonce);
      break;
    }
    case Request_t::ABORT:
      Abort("aborted by request of '" + request->requested_by + "'");
      PublishStatus(request->nonce);
      break;
    case Request_t::ROLLBACK: {
      const std::string from = models_.CurrentId();
      auto rolled = models_.Rollback();
      if (!rolled) {
        Refuse(*request, "refused: " + rolled.error().message);
        return;
      }
      (void)history_->LogModelEvent(now, "rollback from " + from, models_.CurrentId());
      Transition(Status_t::IDLE, "rolled back from model " + from + " to " + models_.CurrentId());
      PublishStatus(request->nonce);
      break;
    }
  }
}

void Daemon::OnJointState(const BusMessage& message) {
  auto joint_state = DecodeLcm<selfcal::joint_state_t>(message.data, config_.channels.joint_state);
  Record(message);
  if (!joint_state) {
    joint_error_ = joint_state.error().message;
    return;
  }
  if (joint_state->names != joint_names_) {
    joint_error_ = "joint state names do not match the robot model's joints";
    return;
  }
  for (double q : joint_state->positions) {
    if (!std::isfinite(q)) {
      joint_error_ = "joint state has a non-finite position";
      return;
    }
  }
  joint_error_.clear();
  joint_positions_ = joint_state->positions;
  joint_receive_utime_ = message.receive_utime;
}

void Daemon::OnSensor(const BusMessage& message) {
  sensor_receive_utime_ = message.receive_utime;
  Record(message);
}

void Daemon::Record(const BusMessage& message) {
  if (!writer_ || !writer_error_.empty()) return;
  if (auto written = writer_->Write(message.channel, message.receive_utime, message.data);
      !written) {
    writer_error_ = written.error().message;  // acted on in the next Step
  }
}

// --- The session --------------------------------------------------------------------------------

Status Daemon::Step(std::chrono::milliseconds wait) {
  const std::int64_t deadline =
      NowUtime() + std::chrono::duration_cast<std::chrono::microseconds>(wait).count();
  for (;;) {
    const std::int64_t remaining = deadline - NowUtime();
    if (remaining <= 0) break;
    std::int64_t budget_ms = remaining / 1000;
    if (state_ == Status_t::MOVING || state_ == Status_t::RECORDING) {
      budget_ms = std::min<std::int64_t>(
          budget_ms, std::max<std::int64_t>(0, (next_command_utime_ - NowUtime()) / 1000));
    }
    auto handled = bus_->HandleOnce(std::chrono::milliseconds(budget_ms));
    if (!handled) return handled.error();
    if ((state_ == Status_t::MOVING || state_ == Status_t::RECORDING) &&
        NowUtime() >= next_command_utime_) {
      TickMotion(NowUtime());
    }
  }
  const std::int64_t now = NowUtime();
  switch (state_) {
    case Status_t::CHECKING:
      RunChecks();
      break;
    case Status_t::MOVING:
    case Status_t::RECORDING:
      TickMotion(now);
      break;
    case Status_t::CALIBRATING:
    case Status_t::VALIDATING:
      TickCalibration();
      break;
    default:
      break;
  }
  if (NowUtime() - last_status_utime_ >= static_cast<std::int64_t>(1e6 / config_.status_rate_hz)) {
    PublishStatus();
  }
  return OkStatus();
}

void Daemon::StartSession(const Request_t& request, const std::string& plan_name) {
  if (worker_thread_.joinable()) worker_thread_.join();  // done (checked by the caller)
  worker_.reset();
  const std::int64_t now = NowUtime();
  session_ = SessionMeta{};
  session_.id = NewSessionId(now);
  session_.plan = plan_name;
  session_.requested_by = request.requested_by;
  session_.nonce = request.nonce;
  session_.started_utime = now;
  session_.status = "checking";
  record_ = SessionRecord{};
  record_.id = session_.id;
  record_.started_utime = now;
  record_.plan = plan_name;
  record_.requested_by = request.requested_by;
  record_.nonce = request.nonce;
  session_plan_ = plans_.at(plan_name);
  session_model_.reset();
  writer_.reset();
  writer_error_.clear();
  steps_.clear();
  Transition(Status_t::CHECKING, "checking joint states, sensor, plan and storage");
}

void Daemon::RunChecks() {
  const std::int64_t now = NowUtime();
  auto fail = [&](const std::string& why) { EndSession(Status_t::FAILED, "check failed: " + why); };
  auto model = models_.Current();
  if (!model) return fail("the current model is unreadable: " + model.error().message);
  if (const auto problem = CheckPlan(session_plan_, model->model, config_.checks.limit_margin);
      !problem.empty()) {
    return fail(problem);
  }
  // Inputs may lag a restart by a moment: wait for them a little before refusing.
  const bool joints_fresh = joint_receive_utime_ != 0 &&
                            now - joint_receive_utime_ <=
                                static_cast<std::int64_t>(config_.checks.joint_state_max_age * 1e6);
  const bool sensor_fresh =
      sensor_receive_utime_ != 0 &&
      now - sensor_receive_utime_ <= static_cast<std::int64_t>(config_.checks.sensor_max_age * 1e6);
  if ((!joints_fresh || !sensor_fresh) && now - session_.started_utime < kInputGrace) return;
  if (joint_receive_utime_ == 0) {
    return fail("no joint states on " + config_.channels.joint_state +
                (joint_error_.empty() ? std::string() : " usable (" + joint_error_ + ")"));
  }
  const std::int64_t joint_age = now - joint_receive_utime_;
  if (joint_age > static_cast<std::int64_t>(config_.checks.joint_state_max_age * 1e6)) {
    return fail("joint states are stale (last one " + Millis(joint_age) + " ago on " +
                config_.channels.joint_state + ")");
  }
  if (sensor_receive_utime_ == 0)
    return fail("the sensor is silent (nothing on " + config_.channels.sensor + ")");
  const std::int64_t sensor_age = now - sensor_receive_utime_;
  if (sensor_age > static_cast<std::int64_t>(config_.checks.sensor_max_age * 1e6)) {
    return fail("the sensor is silent (last message " + Millis(sensor_age) + " ago on " +
                config_.channels.sensor + ")");
  }
  // Room for the new session: oldest sessions that produced neither the current nor the previous
  // model go.
  std::set<std::string> keep = {models_.CurrentId(), models_.PreviousId()};
  auto removed = sessions_.EnforceQuota(config_.storage.quota_bytes, keep);
  if (!removed) return fail(removed.error().message);
  for (const auto& id : *removed) spdlog::info("storage quota: removed session {}", id);

  session_model_ = std::move(model).value();
  session_.status = "recording";
  if (auto created = sessions_.Create(session_); !created) return fail(created.error().message);
  record_.state = "recording";
  if (auto status = history_->UpsertSession(record_); !status)
    spdlog::warn("{}", status.error().message);
  auto writer = LcmLogWriter::Open(sessions_.RecordingPath(session_.id));
  if (!writer) return fail(writer.error().message);
  writer_.emplace(std::move(writer).value());

  // The motion: to the start of each scan, settle, sweep while recording, settle.
  const auto& robot = session_model_->model;
  std::vector<double> at = joint_positions_;
  for (std::size_t i = 0; i < session_plan_.scans.size(); ++i) {
    const auto& scan = session_plan_.scans[i];
    MotionStep move;
    move.kind = MotionStep::kMove;
    move.motion = PlanMotion(at, scan.from, robot, config_.motion.speed_fraction, 0);
    move.duration = move.motion.duration;
    steps_.push_back(move);
    MotionStep settle;
    settle.kind = MotionStep::kSettle;
    settle.motion = PlanMotion(scan.from, scan.from, robot, 1, 0);
    settle.duration = config_.motion.settle_time;
    steps_.push_back(settle);
    MotionStep sweep;
    sweep.kind = MotionStep::kSweep;
    sweep.motion = PlanSweep(scan, robot);
    // A depth-camera scan (from == to) still records for a moment.
    sweep.duration = std::max(sweep.motion.duration, config_.motion.settle_time);
    sweep.scan_index = static_cast<int>(i);
    sweep.validation = scan.validation;
    steps_.push_back(sweep);
    settle.motion = PlanMotion(scan.to, scan.to, robot, 1, 0);
    steps_.push_back(settle);
    at = scan.to;
  }
  step_index_ = 0;
  step_start_utime_ = NowUtime();
  next_command_utime_ = step_start_utime_;
  Transition(Status_t::MOVING, "moving to scan 1 of " + std::to_string(session_plan_.scans.size()));
}

void Daemon::TickMotion(std::int64_t now) {
  if (!writer_error_.empty()) {
    HoldPosition();
    return EndSession(Status_t::FAILED, "recording failed: " + writer_error_);
  }
  const std::int64_t joint_age = now - joint_receive_utime_;
  if (joint_age > static_cast<std::int64_t>(config_.checks.joint_state_max_age * 1e6)) {
    HoldPosition();
    return EndSession(Status_t::FAILED, "joint states went stale during motion (last one " +
                                            Millis(joint_age) + " ago)");
  }
  const std::int64_t sensor_age = now - sensor_receive_utime_;
  if (sensor_age > static_cast<std::int64_t>(config_.checks.sensor_max_age * 1e6)) {
    HoldPosition();
    return EndSession(Status_t::FAILED,
                      "sensor dropout during motion (last message " + Millis(sensor_age) + " ago)");
  }
  // Deviation: the measured position against the plan near the time of the measurement. The arm
  // follows its setpoints with a lag (transport, controller cycle, servo), so the smallest
  // deviation from the plan over the last `checks.max_lag_s` is what counts.
  if (joint_receive_utime_ >= step_start_utime_) {
    const double t = static_cast<double>(joint_receive_utime_ - step_start_utime_) * 1e-6;
    double best = std::numeric_limits<double>::infinity();
    std::size_t worst_joint = 0;
    for (double lag = 0; lag <= config_.checks.max_lag + 1e-9; lag += 0.005) {
      const auto expected = PlannedAt(t - lag);
      double worst = 0;
      std::size_t joint = 0;
      for (std::size_t j = 0; j < expected.size() && j < joint_positions_.size(); ++j) {
        const double deviation = std::abs(joint_positions_[j] - expected[j]);
        if (deviation > worst) {
          worst = deviation;
          joint = j;
        }
      }
      if (worst < best) {
        best = worst;
        worst_joint = joint;
      }
    }
    if (best > config_.checks.max_deviation) {
      HoldPosition();
      std::ostringstream why;
      why << "joint " << joint_names_[worst_joint] << " deviates from the trajectory by " << best
          << " (limit " << config_.checks.max_deviation << " within " << config_.checks.max_lag
          << " s of lag)";
      return EndSession(Status_t::FAILED, why.str());
    }
  }
  // Advance through finished steps.
  while (step_index_ < steps_.size() &&
         now - step_start_utime_ >= static_cast<std::int64_t>(steps_[step_index_].duration * 1e6)) {
    const auto& done = steps_[step_index_];
    if (done.kind == MotionStep::kSweep) PublishMarker(selfcal::scan_marker_t::END, done);
    step_start_utime_ += static_cast<std::int64_t>(done.duration * 1e6);
    ++step_index_;
    if (step_index_ == steps_.size()) return FinishRecording();
    const auto& next = steps_[step_index_];
    const int scans = static_cast<int>(session_plan_.scans.size());
    if (next.kind == MotionStep::kSweep) {
      PublishMarker(selfcal::scan_marker_t::BEGIN, next);
      Transition(Status_t::RECORDING,
                 "recording scan " + std::to_string(next.scan_index + 1) + " of " +
                     std::to_string(scans) + (next.validation ? " (validation)" : ""),
                 static_cast<float>(next.scan_index) / static_cast<float>(scans));
    } else if (next.kind == MotionStep::kMove) {
      Transition(
          Status_t::MOVING,
          "moving to scan " + std::to_string(step_index_ / 4 + 1) + " of " + std::to_string(scans),
          static_cast<float>(step_index_ / 4) / static_cast<float>(scans));
    }
  }
  const auto& step = steps_[step_index_];
  const double t = static_cast<double>(now - step_start_utime_) * 1e-6;
  drake::lcmt_iiwa_command command;
  command.utime = now;
  command.joint_position = step.motion.At(std::min(t, step.motion.duration));
  command.num_joints = static_cast<std::int32_t>(command.joint_position.size());
  command.num_torques = 0;
  if (auto published = bus_->Publish(config_.channels.arm_command, command); !published) {
    spdlog::warn("{}", published.error().message);
  }
  next_command_utime_ = now + static_cast<std::int64_t>(1e6 / config_.motion.command_rate_hz);
}

std::vector<double> Daemon::PlannedAt(double t) const {
  // `t` [s] relative to the start of the current step; negative reaches into earlier steps.
  std::size_t index = step_index_;
  while (t < 0 && index > 0) {
    --index;
    t += steps_[index].duration;
  }
  const auto& step = steps_[index];
  return step.motion.At(std::clamp(t, 0.0, step.motion.duration));
}

void Daemon::PublishMarker(std::int8_t event, const MotionStep& step) {
  selfcal::scan_marker_t marker;
  marker.utime = NowUtime();
  marker.event = event;
  marker.purpose =
      step.validation ? selfcal::scan_marker_t::VALIDATION : selfcal::scan_marker_t::FIT;
  marker.scan_index = step.scan_index;
  marker.plan_name = session_plan_.name;
  marker.session_id = session_.id;
  if (writer_ && writer_error_.empty()) {
    if (auto written = writer_->Write(config_.channels.scan_marker, marker.utime, marker);
        !written) {
      writer_error_ = written.error().message;
    }
  }
  if (auto published = bus_->Publish(config_.channels.scan_marker, marker); !published) {
    spdlog::warn("{}", published.error().message);
  }
}

void Daemon::HoldPosition() {
  // Stop at once: command the last measured position, so the arm stands where it is.
  if (joint_positions_.empty()) return;
  drake::lcmt_iiwa_command command;
  command.utime = NowUtime();
  command.joint_position = joint_positions_;
  command.num_joints = static_cast<std::int32_t>(joint_positions_.size());
  command.num_torques = 0;
  (void)bus_->Publish(config_.channels.arm_command, command);
}

void Daemon::FinishRecording() {
  auto committed = writer_->Commit();
  writer_.reset();
  if (!committed)
    return EndSession(Status_t::FAILED, "recording failed: " + committed.error().message);
  session_.status = "recorded";
  PersistSession();
  StartCalibration();
}

void Daemon::StartCalibration() {
  session_.status = "calibrating";
  PersistSession();
  calibration_start_utime_ = NowUtime();
  worker_ = std::make_shared<Worker>();
  CalibrationJob job;
  job.session_id = session_.id;
  job.joint_state_channel = config_.channels.joint_state;
  job.scan_marker_channel = config_.channels.scan_marker;
  job.sensor_channel = config_.channels.sensor;
  job.recording_path = sessions_.RecordingPath(session_.id);
  job.model_path = models_.CurrentPath();
  job.current = session_model_->model;
  job.sensor_path = config_.sensor;
  job.threads = config_.calibration_threads;
  Transition(Status_t::CALIBRATING, "calibrating", 0);
  if (!engine_) return EndSession(Status_t::FAILED, "this selfcald has no calibration engine");
  const int nice = config_.calibration_nice;
  worker_thread_ = std::thread([worker = worker_, engine = engine_.get(), job, nice] {
    // Lower priority than the bus loop: Linux applies setpriority to the calling thread.
    setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), nice);
    auto progress = [&worker](double fraction, const std::string& what) {
      if (what.rfind("validation", 0) == 0) worker->phase = 1;
      worker->progress = static_cast<float>(fraction);
      std::lock_guard lock(worker->mutex);
      worker->stage = what;
    };
    auto calibrated = engine->Calibrate(job, progress, worker->stop);
    if (calibrated && !worker->stop && calibrated->validation_rms_before >= 0 &&
        calibrated->validation_rms_after >= 0) {
      std::lock_guard lock(worker->mutex);
      worker->rms_before = calibrated->validation_rms_before;
      worker->rms_after = calibrated->validation_rms_after;
    } else if (calibrated && !worker->stop) {
      worker->phase = 1;
      worker->progress = 0;
      auto before = engine->ValidationRms(job, job.current, worker->stop);
      worker->progress = 0.5;
      auto after = before ? engine->ValidationRms(job, calibrated->model, worker->stop) : before;
      std::lock_guard lock(worker->mutex);
      if (!before || !after)
        worker->error = "validation failed: " + (before ? after : before).error().message;
      else {
        worker->rms_before = *before;
        worker->rms_after = *after;
      }
    }
    {
      std::lock_guard lock(worker->mutex);
      worker->calibrated.emplace(std::move(calibrated));
    }
    worker->done = true;
  });
}

void Daemon::TickCalibration() {
  std::string stage;
  {
    std::lock_guard lock(worker_->mutex);
    stage = worker_->stage;
  }
  if (!worker_->done) {
    if (worker_->phase == 1) {
      Transition(Status_t::VALIDATING, "validating on the held-back scans", worker_->progress);
    } else {
      Transition(Status_t::CALIBRATING, stage.empty() ? "calibrating" : "calibrating: " + stage,
                 worker_->progress);
    }
    return;
  }
  if (worker_thread_.joinable()) worker_thread_.join();
  // The worker has finished: its fields are no longer written, read them without holding the lock
  // (EndSession takes it again).
  auto& calibrated = *worker_->calibrated;
  if (!calibrated)
    return EndSession(Status_t::FAILED, "calibration failed: " + calibrated.error().message);
  record_.iterations = calibrated->iterations;
  record_.runtime = calibrated->runtime;
  if (!worker_->error.empty()) return EndSession(Status_t::FAILED, worker_->error);
  record_.rms_before = worker_->rms_before;
  record_.rms_after = worker_->rms_after;
  // A fast validation may finish between two ticks: the status still shows the stage.
  if (state_ != Status_t::VALIDATING)
    Transition(Status_t::VALIDATING, "validating on the held-back scans", 1);
  if (!calibrated->usable) {
    return EndSession(Status_t::REJECTED,
                      "the engine's result is not usable: " + calibrated->message);
  }
  RestoreRoundOff(session_model_->model, calibrated->model);
  ValidationEvidence validation{worker_->rms_before, worker_->rms_after,
                                calibrated->validation_matches_before,
                                calibrated->validation_matches_after};
  const auto decision =
      ApplyAcceptanceGate(config_.acceptance, session_model_->model, calibrated->model, validation);
  if (!decision.accepted) return EndSession(Status_t::REJECTED, decision.reason);
  std::ostringstream provenance;
  provenance << "{session: \"" << session_.id << "\", from_model: \"" << models_.CurrentId()
             << "\", validation_rms_before: " << worker_->rms_before
             << ", validation_rms_after: " << worker_->rms_after
             << ", iterations: " << calibrated->iterations << "}";
  auto installed = models_.Install(session_.id, calibrated->model, provenance.str());
  if (!installed)
    return EndSession(Status_t::FAILED,
                      "cannot install the new model: " + installed.error().message);
  (void)history_->LogModelEvent(NowUtime(), "accepted", session_.id);
  record_.model_id = session_.id;
  EndSession(Status_t::ACCEPTED, "installed as " + models_.CurrentPath() + "; " + decision.reason);
}

void Daemon::Abort(const std::string& reason) {
  if (state_ == Status_t::MOVING || state_ == Status_t::RECORDING) HoldPosition();
  if (worker_) worker_->stop = true;  // the engine returns soon; its result is discarded
  EndSession(Status_t::ABORTED, reason);
}

void Daemon::PersistSession() {
  if (auto written = sessions_.Write(session_); !written)
    spdlog::warn("{}", written.error().message);
  record_.state = session_.status;
  record_.reason = session_.reason;
  if (auto status = history_->UpsertSession(record_); !status)
    spdlog::warn("{}", status.error().message);
}

void Daemon::EndSession(State outcome, const std::string& reason) {
  const std::int64_t now = NowUtime();
  if (writer_) {
    // Never committed: the log stays .partial and the session says why.
    writer_.reset();
  }
  steps_.clear();
  session_.ended_utime = now;
  session_.reason = reason;
  record_.ended_utime = now;
  session_.status = outcome == Status_t::ACCEPTED   ? "accepted"
                    : outcome == Status_t::REJECTED ? "rejected"
                    : outcome == Status_t::ABORTED  ? "aborted"
                                                    : "failed";
  if (std::filesystem::exists(sessions_.SessionFolder(session_.id))) {
    PersistSession();
  } else {
    record_.state = session_.status;
    record_.reason = reason;
    if (auto status = history_->UpsertSession(record_); !status)
      spdlog::warn("{}", status.error().message);
  }
  Transition(outcome, reason, 1);
  selfcal::calibration_result_t result;
  result.utime = now;
  result.session_id = session_.id;
  result.outcome = outcome == Status_t::ACCEPTED   ? selfcal::calibration_result_t::ACCEPTED
                   : outcome == Status_t::REJECTED ? selfcal::calibration_result_t::REJECTED
                   : outcome == Status_t::ABORTED  ? selfcal::calibration_result_t::ABORTED
                                                   : selfcal::calibration_result_t::FAILED;
  result.reason = reason;
  result.validation_rms_before = record_.rms_before;
  result.validation_rms_after = record_.rms_after;
  result.iterations = record_.iterations;
  result.runtime = record_.runtime;
  result.model_path = outcome == Status_t::ACCEPTED ? models_.ModelPath(models_.CurrentId()) : "";
  result.num_parameters = 0;
  if (worker_ && worker_->done && session_model_) {
    std::lock_guard lock(worker_->mutex);
    if (worker_->calibrated && *worker_->calibrated) {
      const auto& before = session_model_->model;
      const auto& after = (*worker_->calibrated)->model;
      const auto k_before = ToParameterVector(before);
      const auto k_after = ToParameterVector(after);
      const auto& stddev = (*worker_->calibrated)->stddev;
      for (std::size_t i = 0; i < k_before.size() && i < k_after.size(); ++i) {
        if (!before.mask[i]) continue;
        result.parameter_names.push_back(ParameterName(before, i));
        result.parameters_before.push_back(k_before[i]);
        result.parameters_after.push_back(k_after[i]);
        result.parameter_stddev.push_back(i < stddev.size() ? stddev[i] : -1.0);
      }
      result.num_parameters = static_cast<std::int32_t>(result.parameter_names.size());
    }
  }
  if (auto published = bus_->Publish(config_.channels.calibration_result, result); !published) {
    spdlog::warn("{}", published.error().message);
  }
  {
    std::set<std::string> keep = {models_.CurrentId(), models_.PreviousId()};
    if (auto removed = sessions_.EnforceQuota(config_.storage.quota_bytes, keep); removed) {
      for (const auto& id : *removed) spdlog::info("storage quota: removed session {}", id);
    }
  }
  Transition(Status_t::IDLE, std::string("ready; last session ") + session_.id + " " +
                                 StateName(outcome) + "; current model " + models_.CurrentId());
}

}  // namespace selfcal::daemon
