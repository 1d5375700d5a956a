#include "daemon/daemon.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>
#include <limits>
#include <set>
#include <sstream>

#include "core/util/printable.h"
#include "core/util/release.h"
#include "daemon/gate.h"
#include "daemon/remaster.h"
#include "daemon/result_message.h"
#include "daemon/session_report.h"
#include "protocols/fri/fri_messages.h"
#include "protocols/model_file/sensor_config.h"
#include "selfcal/calibration_status_t.hpp"
#include "selfcal/joint_state_t.hpp"
#include "selfcal/robot_driver_status_t.hpp"
#include "selfcal/scan_marker_t.hpp"

namespace selfcal::daemon {
namespace {

using Request_t = selfcal::calibration_request_t;
using Marker_t = selfcal::scan_marker_t;
// How long CHECKING waits for joint states and sensor data to become fresh [us]: a driver that
// restarted with the request needs a moment.
constexpr std::int64_t kInputGrace = 2'000'000;
// The arm's driver reports at 10 Hz and on every event: silent for this long [us] is gone.
constexpr std::int64_t kDriverStatusMaxAge = 1'000'000;
// Requests waiting to be handled (each at most kMaxRequestBytes once handled; liblcm holds them
// whole before that), and authentic ones waiting for their batch's commit.
constexpr int kRequestQueueCapacity = 1000;
// Refused requests are logged in full once per reason per interval, counted otherwise; at most
// kRefusalAnswers of them per second are answered on the status channel.
constexpr std::chrono::seconds kRefusalLogInterval{10};
constexpr int kRefusalAnswers = 20;

void WarnIfFailed(const Status& status) {
  if (!status) spdlog::warn("{}", status.error().message);
}

// True when written; the failure logged.
bool Written(const Status& status) {
  WarnIfFailed(status);
  return status.ok();
}

}  // namespace

Expected<std::unique_ptr<Daemon>> Daemon::Create(const DaemonConfig& config,
                                                 std::shared_ptr<Bus> bus,
                                                 std::unique_ptr<CalibrationEngine> engine,
                                                 UrdfExporter urdf_exporter,
                                                 std::shared_ptr<const Clock> clock) {
  auto key = auth::ReadKeyFile(config.key_file, /*require_private=*/true);
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
  auto history =
      History::Open(config.storage.folder + "/history.sqlite", false, config.storage.requests_kept);
  if (!history) return history.error();
  if (!clock) clock = std::make_shared<SystemClock>();
  std::unique_ptr<Daemon> daemon(new Daemon(
      config, std::move(bus), std::move(engine), *key, SessionStore(config.storage.folder),
      std::move(models).value(), std::move(history).value(), std::move(clock)));
  if (auto loaded = daemon->Load(); !loaded) return loaded.error();
  daemon->Subscribe();
  daemon->Transition(State::kIdle, "ready; current model " + daemon->models_.CurrentId());
  return daemon;
}

Daemon::Daemon(DaemonConfig config, std::shared_ptr<Bus> bus,
               std::unique_ptr<CalibrationEngine> engine, auth::Key key, SessionStore sessions,
               ModelStore models, std::unique_ptr<History> history,
               std::shared_ptr<const Clock> clock)
    : config_(std::move(config)),
      bus_(std::move(bus)),
      clock_(std::move(clock)),
      engine_(std::move(engine)),
      authenticator_(key, config_.robot_id, config_.request_window),
      sessions_(std::move(sessions)),
      models_(std::move(models)),
      history_(std::move(history)),
      motion_(bus_, config_.channels.joint_trajectory, config_.checks, key),
      runner_(engine_.get()),
      refusals_([](LogLevel, const std::string& line) { spdlog::warn("{}", line); }, 1,
                kRefusalLogInterval),
      answers_(kRefusalAnswers, 1'000'000) {}

Status Daemon::Load() {
  auto current = models_.Current();
  if (!current) return current.error();
  for (const auto& joint : current->model.joints) joint_names_.push_back(joint.name);
  for (const auto& [name, path] : config_.plans) {
    auto plan = ReadScanPlan(path);
    if (!plan) return plan.error();
    const std::string problem = CheckPlan(*plan, current->model, config_.checks.limit_margin);
    if (!problem.empty()) return Error{path + ": " + problem};
    plans_[name] = std::move(plan).value();
  }
  // A crash (kill -9, power loss) may have left sessions half done: say so, on disk and in the
  // history.
  const std::int64_t now = clock_->Now();
  auto interrupted = sessions_.MarkInterrupted(now);
  if (!interrupted) return interrupted.error();
  MarkInterrupted(*interrupted, now);
  // The driver executes a whole trajectory on its own: a daemon killed in motion leaves the arm
  // moving, so its successor stops it.
  if (!interrupted->empty()) motion_.StopDriver(interrupted->back(), now);
  // Nonces used before a restart stay used, whatever the clock says now.
  auto nonces = history_->NoncesSince(std::numeric_limits<std::int64_t>::min());
  if (!nonces) return nonces.error();
  for (const auto& [nonce, utime] : *nonces) authenticator_.RememberNonce(nonce, utime);
  auto forgotten = history_->ForgottenNoncesUpTo();
  if (!forgotten) return forgotten.error();
  authenticator_.RefuseUpTo(*forgotten);
  return OkStatus();
}

void Daemon::MarkInterrupted(const std::vector<std::string>& ids, std::int64_t now) {
  for (const auto& id : ids) {
    SessionRecord record;
    record.id = id;
    if (auto meta = sessions_.Read(id); meta) {
      record.started_utime = meta->started_utime;
      record.plan = meta->plan;
      record.requested_by = meta->requested_by;
      record.nonce = meta->nonce;
      record.reason = meta->reason;
    }
    record.ended_utime = now;
    record.state = "incomplete";
    WarnIfFailed(history_->UpsertSession(record));
    // Killed while installing, the session leaves its model folder half written (or complete but
    // never made current): it is not a model anyone can roll back to, only space taken.
    WarnIfFailed(models_.DiscardUninstalled(id));
    spdlog::warn("session {} was interrupted; marked incomplete", id);
  }
}

void Daemon::Subscribe() {
  const auto& channels = config_.channels;
  // Room for a second of a flood of forged requests while a session step takes long (an fsync):
  // the signed ABORT behind them must not be dropped.
  bus_->SubscribeWithQueue(
      channels.calibration_request, [this](const BusMessage& m) { OnRequest(m); },
      kRequestQueueCapacity);
  bus_->Subscribe(channels.joint_state, [this](const BusMessage& m) { OnJointState(m); });
  bus_->Subscribe(channels.sensor, [this](const BusMessage& m) { OnSensor(m); });
  bus_->Subscribe(channels.robot_status, [this](const BusMessage& m) { OnDriverStatus(m); });
}

// --- Status -------------------------------------------------------------------------------------

// A change of state or message is published at once; a change of progress alone waits for the
// periodic status (the engine reports progress many times a second).
void Daemon::Transition(State state, const std::string& message, float progress) {
  const std::string session = session_.id.empty() ? "" : session_.id + ": ";
  const bool changed = state != state_ || message != message_;
  if (state != state_) {
    spdlog::info("{} {}{}", StateName(state), session, message);
  } else if (message != message_) {
    spdlog::debug("{} {}{}", StateName(state), session, message);
  }
  state_ = state;
  message_ = message;
  progress_ = progress;
  if (changed) PublishStatus();
}

selfcal::calibration_status_t Daemon::MakeStatus() const {
  selfcal::calibration_status_t status;
  status.utime = clock_->Now();
  status.state = ToWire(state_);
  status.session_id = state_ == State::kIdle ? "" : session_.id;
  status.progress = progress_;
  status.message = message_;
  status.last_session_id = last_session_id_;
  status.last_session_state = last_session_id_.empty() ? -1 : ToWire(last_session_state_);
  return status;
}

void Daemon::PublishStatus(const std::string& request_nonce) {
  selfcal::calibration_status_t status = MakeStatus();
  status.request_nonce = request_nonce;
  WarnIfFailed(bus_->Publish(config_.channels.calibration_status, status));
  last_status_time_ = clock_->Monotonic();
}

void Daemon::Refuse(const Request_t& request, const std::string& why) {
  // The refusal answers the request without changing the state: a status naming its nonce (if
  // it is of a nonce's size: a refusal echoes nothing unbounded) with the reason in its own
  // field. It leaves the periodic status on its own schedule.
  selfcal::calibration_status_t status = MakeStatus();
  status.request_nonce = request.nonce.size() <= kMaxNonceChars ? request.nonce : std::string();
  status.refusal = why;
  WarnIfFailed(bus_->Publish(config_.channels.calibration_status, status));
}

void Daemon::CountRefusal(const std::string& reason, const std::string& details,
                          std::int64_t time) {
  refusals_.Log(LogLevel::kWarning, reason, "refused a request: " + reason + ": " + details,
                RateLimitedLog::Clock::time_point(std::chrono::microseconds(time)));
}

// --- Inputs -------------------------------------------------------------------------------------

void Daemon::OnRequest(const BusMessage& message) {
  const std::int64_t now = clock_->Now();  // the request's age and the history's stamps
  const std::int64_t time = clock_->Monotonic();
  // Nothing about a request is stored, and little logged, before it authenticates.
  if (message.data.size() > kMaxRequestBytes) {
    trim_memory_ = true;
    return CountRefusal("request too large",
                        std::to_string(message.data.size()) + " bytes (at most " +
                            std::to_string(kMaxRequestBytes) + ")",
                        time);
  }
  auto request = DecodeLcm<Request_t>(message.data, config_.channels.calibration_request);
  if (!request) {
    return CountRefusal("request does not decode", Printable(request.error().message, 200), time);
  }
  const Verdict verdict = authenticator_.Check(*request, now);
  if (verdict != Verdict::kAccepted) {
    CountRefusal(VerdictReason(verdict), DescribeRequest(*request), time);
    if (answers_.Take(time)) Refuse(*request, VerdictText(verdict));
    return;
  }
  // Decided, stored and answered with the other requests of this turn of the bus (one commit
  // for all: a commit per request cannot keep up with a flood of authentic requests).
  pending_.push_back({std::move(request).value(), now});
  if (pending_.size() >= static_cast<std::size_t>(kRequestQueueCapacity)) HandleRequests();
}

// Requests are decided in order, each against the situation the requests before it left, and
// none is answered or acted on before its nonce is on disk: a restarted daemon knows only the
// nonces of the history. So the batch goes in chunks that end at a request to act on (acting
// changes the situation of the next ones): a flood of refused requests is one commit per batch.
// Once a write fails (the history locked or its disk full) the rest of the batch is refused
// without another try: each try can wait the history's busy timeout, and the loop that supervises
// the motion must not wait that long for every chunk of a flood.
void Daemon::HandleRequests() {
  std::vector<PendingRequest> batch;
  batch.swap(pending_);
  const std::int64_t time = clock_->Monotonic();
  std::vector<RequestDecision> decisions;
  std::vector<RequestRow> rows;
  Status logged = OkStatus();
  for (std::size_t begin = 0; begin < batch.size();) {
    const std::size_t end = DecideChunk(batch, begin, decisions, rows);
    if (logged) logged = history_->LogRequests(rows);
    for (std::size_t i = begin; i < end; ++i) {
      AnswerRequest(batch[i].request, decisions[i - begin], logged, time);
    }
    begin = end;
  }
}

// Decides the requests of `batch` from `begin` in the daemon's situation now, up to and including
// the first one accepted; returns where the next chunk begins.
std::size_t Daemon::DecideChunk(const std::vector<PendingRequest>& batch, std::size_t begin,
                                std::vector<RequestDecision>& decisions,
                                std::vector<RequestRow>& rows) const {
  const Situation situation{state_, session_.id, runner_.busy()};
  decisions.clear();
  rows.clear();
  std::size_t end = begin;
  while (end < batch.size()) {
    const Request_t& request = batch[end].request;
    decisions.push_back(
        DecideRequest(Verdict::kAccepted, request, situation, config_.default_plan, config_.plans));
    rows.push_back({batch[end].received_utime, request.utime, request.nonce, request.action,
                    request.requested_by, decisions.back().text(), true});
    ++end;
    if (decisions.back().accepted()) break;
  }
  return end;
}

// Acts on a decided request whose row was written (`logged`), else refuses it; answers it.
void Daemon::AnswerRequest(const Request_t& request, RequestDecision& decision,
                           const Status& logged, std::int64_t time) {
  // An ABORT is the exception: stopping the arm must not depend on the disk (its nonce is still
  // remembered until this daemon stops).
  if (!logged && request.action == Request_t::ABORT) {
    spdlog::error("{}", logged.error().message);
  } else if (!logged) {
    decision.refusal = Refusal::kUnrecorded;
    decision.reason = "cannot record the request in the history (" + logged.error().message + ")";
  }
  if (decision.accepted()) {
    spdlog::info("request {}: {}", DescribeRequest(request), decision.text());
    return Act(request, decision);
  }
  // Counted per reason as the forged ones are: a key holder's runaway script must not fill the
  // journal either. Each is answered; the history has every one that could be written.
  CountRefusal(RefusalName(decision.refusal), DescribeRequest(request) + ": " + decision.reason,
               time);
  Refuse(request, decision.text());
}

void Daemon::Act(const Request_t& request, const RequestDecision& decision) {
  switch (request.action) {
    case Request_t::START:
      StartSession(request, decision.plan);
      break;
    case Request_t::ABORT:
      Abort("aborted by request of '" + Printable(request.requested_by) + "'");
      break;
    case Request_t::ROLLBACK: {
      const std::string from = models_.CurrentId();
      if (auto rolled = models_.Rollback(); !rolled) {
        const std::string why = RefusedText("rollback failed: " + rolled.error().message);
        WarnIfFailed(history_->SetRequestVerdict(request.nonce, why));
        spdlog::warn("{}", why);
        return Refuse(request, why);
      }
      WarnIfFailed(
          history_->LogModelEvent(clock_->Now(), "rollback from " + from, models_.CurrentId()));
      Transition(State::kIdle, "rolled back from model " + from + " to " + models_.CurrentId());
      break;
    }
  }
  PublishStatus(request.nonce);
}

void Daemon::OnJointState(const BusMessage& message) {
  recorder_.Write(message.channel, message.receive_utime, message.data);
  auto joint_state = DecodeLcm<selfcal::joint_state_t>(message.data, config_.channels.joint_state);
  if (!joint_state) {
    inputs_.joint_error = joint_state.error().message;
    return;
  }
  if (joint_state->names != joint_names_) {
    inputs_.joint_error = "joint state names do not match the robot model's joints";
    return;
  }
  if (!std::all_of(joint_state->positions.begin(), joint_state->positions.end(),
                   [](double q) { return std::isfinite(q); })) {
    inputs_.joint_error = "joint state has a non-finite position";
    return;
  }
  inputs_.joint_error.clear();
  inputs_.joint_positions = joint_state->positions;
  inputs_.joint_time = clock_->Monotonic();
}

void Daemon::OnSensor(const BusMessage& message) {
  inputs_.sensor_time = clock_->Monotonic();
  recorder_.Write(message.channel, message.receive_utime, message.data);
}

void Daemon::OnDriverStatus(const BusMessage& message) {
  auto status = DecodeLcm<selfcal::robot_driver_status_t>(message.data, message.channel);
  if (!status) return;
  inputs_.driver_time = clock_->Monotonic();
  inputs_.driver_session_state = status->session_state;
  inputs_.driver_source = status->command_source;
  motion_.OnDriverStatus(*status);
}

// --- The session --------------------------------------------------------------------------------

Status Daemon::Step(std::chrono::milliseconds wait) {
  if (const std::int64_t due = motion_.next_deadline(); due > 0) {
    const std::int64_t until_due_ms =
        std::max<std::int64_t>(0, (due - clock_->Monotonic() + 999) / 1000);
    wait = std::min(wait, std::chrono::milliseconds(until_due_ms));
  }
  if (auto serviced = ServiceBus(*bus_, true, wait); !serviced) return serviced.error();
  HandleRequests();
  switch (state_) {
    case State::kChecking:
      RunChecks();
      break;
    case State::kMoving:
    case State::kRecording:
      TickMotion();
      break;
    case State::kCalibrating:
    case State::kValidating:
      TickCalibration();
      break;
    default:
      break;
  }
  const std::int64_t now = clock_->Monotonic();
  refusals_.Flush(RateLimitedLog::Clock::time_point(std::chrono::microseconds(now)));
  // liblcm reassembled a large forged request whole before we could refuse it; give the memory
  // back (at most once a second).
  if (trim_memory_ && now - last_trim_time_ >= 1'000'000) {
    ReturnFreedMemory();
    trim_memory_ = false;
    last_trim_time_ = now;
  }
  if (now - last_status_time_ >= Us(1.0 / config_.status_rate_hz)) PublishStatus();
  if (!unsaved_ends_.empty() && now - last_save_retry_time_ >= 1'000'000) RetryUnsavedEnds(now);
  return OkStatus();
}

void Daemon::RetryUnsavedEnds(std::int64_t now) {
  last_save_retry_time_ = now;
  std::erase_if(unsaved_ends_, [this](const UnsavedEnd& end) {
    // Quietly: the first failure was logged, and a full disk would repeat it every second.
    if (end.has_folder && !sessions_.Write(end.meta).ok()) return false;
    if (!history_->UpsertSession(end.record).ok()) return false;
    spdlog::info("session {}: its end ({}) is recorded now", end.meta.id, end.meta.status);
    return true;
  });
}

void Daemon::StartSession(const Request_t& request, const std::string& plan_name) {
  runner_.Reset();  // not busy: the request policy checked
  const std::int64_t now = clock_->Now();
  session_ = SessionMeta{};
  session_.id = NewSessionId(now);
  session_.plan = plan_name;
  session_.requested_by = request.requested_by;
  session_.nonce = request.nonce;
  session_.started_utime = now;
  session_.status = "checking";
  session_start_time_ = clock_->Monotonic();
  record_ = SessionRecord{};
  record_.id = session_.id;
  record_.started_utime = now;
  record_.plan = plan_name;
  record_.requested_by = request.requested_by;
  record_.nonce = request.nonce;
  session_plan_ = plans_.at(plan_name);
  session_model_.reset();
  engine_start_.reset();
  calibrated_.reset();
  recorder_.Discard();
  Transition(State::kChecking, "checking joint states, sensor, plan and storage");
}

// Empty when the inputs are fresh, nullopt while they may still become so, else the problem.
std::optional<std::string> Daemon::InputProblem(std::int64_t now) const {
  const std::int64_t joint_age = now - inputs_.joint_time;
  const std::int64_t sensor_age = now - inputs_.sensor_time;
  const bool joints_fresh =
      inputs_.joint_time != 0 && joint_age <= Us(config_.checks.joint_state_max_age);
  const bool sensor_fresh =
      inputs_.sensor_time != 0 && sensor_age <= Us(config_.checks.sensor_max_age);
  const std::string driver = DriverProblem(now);
  if (joints_fresh && sensor_fresh && driver.empty()) return std::string();
  if (now - session_start_time_ < kInputGrace) return std::nullopt;
  const auto& channels = config_.channels;
  if (inputs_.joint_time == 0) {
    return "no joint states on " + channels.joint_state +
           (inputs_.joint_error.empty() ? std::string() : " usable (" + inputs_.joint_error + ")");
  }
  if (!joints_fresh) {
    return "joint states are stale (last one " + Millis(joint_age) + " ago on " +
           channels.joint_state + ")";
  }
  if (inputs_.sensor_time == 0) return "the sensor is silent (nothing on " + channels.sensor + ")";
  if (!sensor_fresh) {
    return "the sensor is silent (last message " + Millis(sensor_age) + " ago on " +
           channels.sensor + ")";
  }
  return driver;
}

// Empty when the arm's driver can take a trajectory now: its FRI session is COMMANDING_ACTIVE
// and it holds the arm (not executing, following a stream or braking).
std::string Daemon::DriverProblem(std::int64_t now) const {
  using DriverStatus_t = selfcal::robot_driver_status_t;
  constexpr int kCommandingActive = static_cast<int>(fri::SessionState::kCommandingActive);
  const std::string& channel = config_.channels.robot_status;
  if (inputs_.driver_time == 0) return "no status from the arm's driver on " + channel;
  const std::int64_t age = now - inputs_.driver_time;
  if (age > kDriverStatusMaxAge) {
    return "the arm's driver is silent (last status " + Millis(age) + " ago on " + channel + ")";
  }
  const int state = inputs_.driver_session_state;
  if (state != kCommandingActive) {
    return std::string("the arm's driver is not commanding the arm (FRI session ") +
           (state >= 0 && state < kCommandingActive
                ? fri::ToString(static_cast<fri::SessionState>(state))
                : "unknown") +
           ")";
  }
  if (inputs_.driver_source != DriverStatus_t::SOURCE_HOLD) {
    return "the arm's driver is busy (command source " + std::to_string(inputs_.driver_source) +
           ", not holding)";
  }
  return {};
}

void Daemon::RunChecks() {
  auto fail = [&](const std::string& why) { EndSession(State::kFailed, "check failed: " + why); };
  auto model = models_.Current();
  if (!model) return fail("the current model is unreadable: " + model.error().message);
  if (const auto problem = CheckPlan(session_plan_, model->model, config_.checks.limit_margin);
      !problem.empty()) {
    return fail(problem);
  }
  const auto inputs = InputProblem(clock_->Monotonic());
  if (!inputs) return;  // waiting for the inputs
  if (!inputs->empty()) return fail(*inputs);
  session_model_ = std::move(model).value();
  if (auto prepared = PrepareStorage(); !prepared) return fail(prepared.error().message);
  StartMotion();
}

// Room for the new session (the oldest sessions that produced neither the current nor the
// previous model go), its folder, its history row and its log.
Status Daemon::PrepareStorage() {
  std::set<std::string> keep = {models_.CurrentId(), models_.PreviousId()};
  auto removed = sessions_.EnforceQuota(config_.storage.quota_bytes, keep, history_->FileBytes());
  if (!removed) return removed.error();
  for (const auto& id : *removed) spdlog::info("storage quota: removed session {}", id);
  session_.status = "recording";
  if (auto created = sessions_.Create(session_); !created) return created.error();
  record_.state = "recording";
  WarnIfFailed(history_->UpsertSession(record_));
  return recorder_.Open(sessions_.RecordingPath(session_.id));
}

void Daemon::StartMotion() {
  auto motion = PlanScanMotion(session_plan_, inputs_.joint_positions, session_model_->model,
                               config_.motion.speed_fraction, config_.motion.settle_time);
  if (!motion)
    return EndSession(State::kFailed, "cannot plan the motion: " + motion.error().message);
  if (auto started = motion_.Start(std::move(motion).value(), joint_names_, session_.id,
                                   clock_->Monotonic(), clock_->Now());
      !started) {
    return EndSession(State::kFailed, "cannot command the arm: " + started.error().message);
  }
  Transition(State::kMoving, "moving to scan 1 of " + std::to_string(session_plan_.scans.size()));
}

void Daemon::TickMotion() {
  if (!recorder_.error().empty()) {
    return EndSession(State::kFailed, "recording failed: " + recorder_.error());
  }
  const MotionInputs inputs{inputs_.joint_time, &inputs_.joint_positions, inputs_.sensor_time};
  for (const MotionEvent& event : motion_.Tick(clock_->Monotonic(), clock_->Now(), inputs)) {
    OnMotionEvent(event);
    if (!IsInMotion(state_)) return;  // the session ended or moved on
  }
}

void Daemon::OnMotionEvent(const MotionEvent& event) {
  const int scans = static_cast<int>(session_plan_.scans.size());
  const int number = event.scan.scan_index + 1;
  const float progress = static_cast<float>(event.scan.scan_index) / static_cast<float>(scans);
  switch (event.kind) {
    case MotionEvent::Kind::kMoveToScan:
      Transition(State::kMoving,
                 "moving to scan " + std::to_string(number) + " of " + std::to_string(scans),
                 progress);
      break;
    case MotionEvent::Kind::kScanBegin:
      PublishMarker(Marker_t::BEGIN, event.scan);
      Transition(State::kRecording,
                 "recording scan " + std::to_string(number) + " of " + std::to_string(scans) +
                     (event.scan.validation ? " (validation)" : ""),
                 progress);
      break;
    case MotionEvent::Kind::kScanEnd:
      PublishMarker(Marker_t::END, event.scan);
      break;
    case MotionEvent::Kind::kCompleted:
      FinishRecording();
      break;
    case MotionEvent::Kind::kFailed:
      EndSession(State::kFailed, event.reason);
      break;
  }
}

void Daemon::PublishMarker(std::int8_t event, const ScanTiming& scan) {
  Marker_t marker;
  marker.utime = clock_->Now();
  marker.event = event;
  marker.purpose = scan.validation ? Marker_t::VALIDATION : Marker_t::FIT;
  marker.scan_index = scan.scan_index;
  marker.plan_name = session_plan_.name;
  marker.session_id = session_.id;
  recorder_.Write(config_.channels.scan_marker, marker.utime, marker);
  WarnIfFailed(bus_->Publish(config_.channels.scan_marker, marker));
}

void Daemon::FinishRecording() {
  if (auto committed = recorder_.Commit(); !committed) {
    return EndSession(State::kFailed, "recording failed: " + committed.error().message);
  }
  session_.status = "recorded";
  PersistSession();
  StartCalibration();
}

void Daemon::StartCalibration() {
  session_.status = "calibrating";
  PersistSession();
  CalibrationJob job;
  job.session_id = session_.id;
  job.joint_state_channel = config_.channels.joint_state;
  job.scan_marker_channel = config_.channels.scan_marker;
  job.sensor_channel = config_.channels.sensor;
  job.recording_path = sessions_.RecordingPath(session_.id);
  job.model_path = models_.CurrentPath();
  job.current = session_model_->model;
  std::string what = "calibrating";
  if (session_plan_.mode == PlanMode::kRemaster) {
    auto start = RemasterStart(session_model_->model);
    if (!start) return EndSession(State::kFailed, "cannot remaster: " + start.error().message);
    job.current = std::move(*start);
    const auto free = std::count(job.current.mask.begin(), job.current.mask.end(), true);
    what = "remastering: only the joints' zero offsets and the sensor mount, " +
           std::to_string(free) + " parameters";
  }
  engine_start_ = job.current;
  job.sensor_path = config_.sensor;
  job.threads = config_.calibration_threads;
  Transition(State::kCalibrating, what, 0);
  if (!runner_.has_engine()) {
    return EndSession(State::kFailed, "this selfcald has no calibration engine");
  }
  runner_.Start(job, config_.calibration_nice);
}

void Daemon::TickCalibration() {
  if (!runner_.done()) {
    const auto progress = runner_.progress();
    if (progress.phase == Phase::kValidating) {
      Transition(State::kValidating, "validating on the held-back scans", progress.fraction);
    } else {
      const std::string word =
          session_plan_.mode == PlanMode::kRemaster ? "remastering" : "calibrating";
      Transition(State::kCalibrating, progress.stage.empty() ? word : word + ": " + progress.stage,
                 progress.fraction);
    }
    return;
  }
  const auto& result = *runner_.result();
  if (!result) return EndSession(State::kFailed, "calibration failed: " + result.error().message);
  Conclude(*result);
}

// The engine's result through the acceptance gate.
void Daemon::Conclude(const CalibratedModel& result) {
  calibrated_ = result;
  record_.iterations = result.iterations;
  record_.runtime = result.runtime;
  record_.change = result.change;
  // Without validation scans the session failed (nothing to judge), rather than being rejected.
  if (result.validation_rms_before < 0 || result.validation_rms_after < 0) {
    return EndSession(State::kFailed, "validation failed: the recording has no validation scans");
  }
  record_.rms_before = result.validation_rms_before;
  record_.rms_after = result.validation_rms_after;
  // A fast validation may finish between two ticks: the status still shows the stage.
  if (state_ != State::kValidating) {
    Transition(State::kValidating, "validating on the held-back scans", 1);
  }
  // The gate's rules, against what the engine was allowed to change (nothing else may move).
  DaemonConfig judging = config_;
  if (session_plan_.mode == PlanMode::kRemaster) {
    judging.acceptance = RemasterAcceptance(config_.acceptance);
  }
  const auto decision = JudgeCalibration(judging.acceptance, *engine_start_, *calibrated_);
  if (session_plan_.mode == PlanMode::kRemaster) AddRemasterCorrections();
  report_ = std::async(
      std::launch::async,
      [config = std::move(judging),
       report = SessionReport{sessions_.SessionFolder(session_.id) + "/report.html", session_.id,
                              sessions_.RecordingPath(session_.id), models_.CurrentId(),
                              *engine_start_, *calibrated_, decision}] {
        WarnIfFailed(WriteSessionReport(config, report));
      });
  if (!decision.accepted) return EndSession(State::kRejected, decision.reason);
  Install(decision.reason);
}

// A remastering's answer per axis, as a controller takes it, in the result message, the history
// and the report; the model to install keeps the model file's mask (a later full session frees
// everything again).
void Daemon::AddRemasterCorrections() {
  calibrated_->model.mask = session_model_->model.mask;
  const RemasterCorrections corrections =
      DescribeRemaster(session_model_->model, calibrated_->model, "the installed model");
  calibrated_->change += (calibrated_->change.empty() ? "" : "; ") + corrections.summary;
  calibrated_->calibration_yaml += corrections.yaml;
  record_.change = calibrated_->change;
  spdlog::info("session {}: {}", session_.id, corrections.summary);
}

void Daemon::Install(const std::string& gate_reason) {
  std::ostringstream provenance;
  provenance << "{session: \"" << session_.id << "\", from_model: \"" << models_.CurrentId()
             << "\", validation_rms_before: " << record_.rms_before
             << ", validation_rms_after: " << record_.rms_after
             << ", iterations: " << calibrated_->iterations << "}";
  auto installed = models_.Install(session_.id, calibrated_->model, provenance.str());
  if (!installed) {
    return EndSession(State::kFailed, "cannot install the new model: " + installed.error().message);
  }
  WarnIfFailed(history_->LogModelEvent(clock_->Now(), "accepted", session_.id));
  record_.model_id = session_.id;
  EndSession(State::kAccepted, "installed as " + models_.CurrentPath() + "; " + gate_reason);
}

void Daemon::Abort(const std::string& reason) {
  runner_.RequestStop();  // the engine returns soon; its result is discarded
  EndSession(State::kAborted, reason);
}

bool Daemon::PersistSession() {
  const bool meta = Written(sessions_.Write(session_));
  record_.state = session_.status;
  record_.reason = session_.reason;
  return Written(history_->UpsertSession(record_)) && meta;
}

void Daemon::EndSession(State outcome, const std::string& reason) {
  const std::int64_t now = clock_->Now();
  motion_.Stop(now);    // the arm stands where it is
  recorder_.Discard();  // never committed: the log stays .partial and the session says why
  session_.ended_utime = now;
  session_.reason = reason;
  session_.status = OutcomeWord(outcome);
  record_.ended_utime = now;
  const bool has_folder = std::filesystem::exists(sessions_.SessionFolder(session_.id));
  bool saved = false;
  if (has_folder) {
    saved = PersistSession();
  } else {
    record_.state = session_.status;
    record_.reason = reason;
    saved = Written(history_->UpsertSession(record_));
  }
  if (!saved) unsaved_ends_.push_back({session_, record_, has_folder});
  last_session_id_ = session_.id;
  last_session_state_ = outcome;
  Transition(outcome, reason, 1);
  PublishResult(outcome, reason, now);
  std::set<std::string> keep = {models_.CurrentId(), models_.PreviousId()};
  if (auto removed =
          sessions_.EnforceQuota(config_.storage.quota_bytes, keep, history_->FileBytes());
      removed) {
    for (const auto& id : *removed) spdlog::info("storage quota: removed session {}", id);
  }
  Transition(State::kIdle, std::string("ready; last session ") + session_.id + " " +
                               StateName(outcome) + "; current model " + models_.CurrentId());
}

void Daemon::PublishResult(State outcome, const std::string& reason, std::int64_t now) {
  SessionOutcome ended;
  ended.outcome = outcome;
  ended.reason = reason;
  ended.utime = now;
  ended.model_path = models_.ModelPath(models_.CurrentId());
  ended.record = &record_;
  ended.before = engine_start_    ? &*engine_start_
                 : session_model_ ? &session_model_->model
                                  : nullptr;
  ended.after = calibrated_ ? &*calibrated_ : nullptr;
  WarnIfFailed(
      bus_->Publish(config_.channels.calibration_result, MakeResultMessage(session_.id, ended)));
}

}  // namespace selfcal::daemon
