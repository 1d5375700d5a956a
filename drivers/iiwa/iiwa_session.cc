#include "drivers/iiwa/iiwa_session.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "protocols/trajectory/trajectory_message.h"

namespace selfcal::iiwa {
namespace {

using Status_t = selfcal::robot_driver_status_t;
constexpr int kActive = static_cast<int>(fri::SessionState::kCommandingActive);
constexpr int kWait = static_cast<int>(fri::SessionState::kCommandingWait);

std::string SourceName(std::int8_t source) {
  switch (source) {
    case Status_t::SOURCE_HOLD:
      return "holding";
    case Status_t::SOURCE_TRAJECTORY:
      return "executing a trajectory";
    case Status_t::SOURCE_STREAM:
      return "following IIWA_COMMAND";
    case Status_t::SOURCE_STOPPING:
      return "stopping";
    default:
      return "not commanding";
  }
}

std::int64_t DeviceUs(const fri::MonitoringMessage& m, std::int64_t host_us) {
  if (m.monitor_data && m.monitor_data->timestamp) {
    return static_cast<std::int64_t>(m.monitor_data->timestamp->sec) * 1000000 +
           m.monitor_data->timestamp->nanosec / 1000;
  }
  return host_us;
}

// Why a datagram is not a monitoring message this session can use; empty when it is.
std::string MonitoringProblem(const fri::MonitoringMessage& m, Eigen::Index joints) {
  if (m.header.message_identifier != fri::kMonitorMessageId) {
    return "not an LBR monitoring message (identifier " +
           std::to_string(m.header.message_identifier) + ")";
  }
  if (!m.connection_info) return "monitoring message without connectionInfo";
  if (!m.monitor_data || !m.monitor_data->measured_joint_position ||
      static_cast<Eigen::Index>(m.monitor_data->measured_joint_position->size()) != joints) {
    return "monitoring message without " + std::to_string(joints) + " measured positions";
  }
  return {};
}

}  // namespace

IiwaSession::IiwaSession(SessionOptions options)
    : options_(std::move(options)), n_(static_cast<Eigen::Index>(options_.joint_names.size())) {
  measured_ = commanded_ = commanded_velocity_ = hold_ = Eigen::VectorXd::Zero(n_);
  events_.reserve(16);
}

std::vector<SessionEvent> IiwaSession::TakeEvents() {
  std::vector<SessionEvent> taken;
  taken.swap(events_);
  return taken;
}

void IiwaSession::Emit(std::int8_t event, const std::string& message) {
  events_.push_back({event, trajectory_id_, message});
}

void IiwaSession::Refuse(const std::string& id, const std::string& reason) {
  // Streams repeat at 200 Hz: the same refusal at most once a second.
  if (reason == last_refusal_ && now_host_us_ - last_refusal_host_us_ < 1000000) return;
  last_refusal_ = reason;
  last_refusal_host_us_ = now_host_us_;
  events_.push_back({Status_t::EVENT_REFUSED, id, reason});
}

std::string IiwaSession::FarFromCurrent(const Eigen::VectorXd& start) const {
  Eigen::Index worst = 0;
  const double distance = (start - hold_).cwiseAbs().maxCoeff(&worst);
  if (distance <= options_.start_tolerance_rad) return {};
  std::ostringstream s;
  s << "starts " << distance << " rad from the current position at "
    << options_.joint_names[static_cast<std::size_t>(worst)] << " (tolerance "
    << options_.start_tolerance_rad << " rad)";
  return s.str();
}

void IiwaSession::StartStopping(const std::string& reason) {
  source_ = Status_t::SOURCE_STOPPING;
  Emit(Status_t::EVENT_STOPPED, reason);
  trajectory_.reset();
  stream_host_us_ = -1;
  stream_.clear();
}

void IiwaSession::Refuse(const std::string& id, const std::string& reason, std::int64_t host_us) {
  now_host_us_ = std::max(now_host_us_, host_us);
  Refuse(id, reason);
}

void IiwaSession::OnTrajectory(const selfcal::joint_trajectory_t& message, std::int64_t host_us) {
  now_host_us_ = std::max(now_host_us_, host_us);
  const std::string& id = message.trajectory_id;
  if (message.num_points == 0) {
    if (source_ == Status_t::SOURCE_TRAJECTORY || source_ == Status_t::SOURCE_STREAM) {
      trajectory_id_ = id.empty() ? trajectory_id_ : id;
      StartStopping("stop requested");
    } else {
      events_.push_back(
          {Status_t::EVENT_STOPPED, id, "stop requested; the arm was " + SourceName(source_)});
    }
    return;
  }
  if (session_state_ != kActive) {
    const std::string state = session_state_ < 0
                                  ? std::string("unknown (no controller)")
                                  : fri::ToString(static_cast<fri::SessionState>(session_state_));
    return Refuse(id, "session is " + state + ", not COMMANDING_ACTIVE");
  }
  if (source_ != Status_t::SOURCE_HOLD) {
    return Refuse(id, "busy: the driver is " + SourceName(source_) +
                          (trajectory_id_.empty() ? "" : " ('" + trajectory_id_ + "')"));
  }
  auto trajectory = FromMessage(message, options_.joint_names);
  if (!trajectory.ok()) return Refuse(id, trajectory.error().message);
  if (auto limits = trajectory::CheckLimits(*trajectory, options_.limits, options_.joint_names);
      !limits.ok()) {
    return Refuse(id, "outside the robot's limits: " + limits.error().message);
  }
  if (trajectory->front().velocity.cwiseAbs().maxCoeff() > 1e-9) {
    return Refuse(id, "does not start at rest");
  }
  if (const std::string far = FarFromCurrent(trajectory->front().position); !far.empty()) {
    return Refuse(id, far);
  }
  start_offset_ = hold_ - trajectory->front().position;
  trajectory_ = std::move(*trajectory);
  trajectory_id_ = id;
  trajectory_start_device_us_ = -1;  // t = 0 at the next cycle
  trajectory_time_ = 0;
  source_ = Status_t::SOURCE_TRAJECTORY;
  std::ostringstream s;
  s << "accepted: " << trajectory_->knots().size() << " knots, " << trajectory_->duration() << " s";
  Emit(Status_t::EVENT_ACCEPTED, s.str());
}

void IiwaSession::OnStreamCommand(const drake::lcmt_iiwa_command& message, std::int64_t host_us) {
  now_host_us_ = std::max(now_host_us_, host_us);
  if (message.num_joints != n_ || static_cast<Eigen::Index>(message.joint_position.size()) != n_) {
    return Refuse("IIWA_COMMAND", "IIWA_COMMAND has " + std::to_string(message.num_joints) +
                                      " joint positions, the robot " + std::to_string(n_) +
                                      " joints");
  }
  if (message.num_torques != 0) {
    return Refuse("IIWA_COMMAND",
                  "IIWA_COMMAND carries torques; only position control is supported");
  }
  const Eigen::VectorXd q = Eigen::Map<const Eigen::VectorXd>(message.joint_position.data(), n_);
  if (!q.allFinite()) return Refuse("IIWA_COMMAND", "IIWA_COMMAND has a non-finite position");
  for (Eigen::Index i = 0; i < n_; ++i) {
    if (q[i] < options_.limits.lower[i] || q[i] > options_.limits.upper[i]) {
      std::ostringstream s;
      s << "IIWA_COMMAND position " << q[i] << " rad of "
        << options_.joint_names[static_cast<std::size_t>(i)] << " is outside ["
        << options_.limits.lower[i] << ", " << options_.limits.upper[i] << "]";
      return Refuse("IIWA_COMMAND", s.str());
    }
  }
  if (session_state_ != kActive) {
    return Refuse("IIWA_COMMAND", "IIWA_COMMAND ignored: session is not COMMANDING_ACTIVE");
  }
  if (source_ == Status_t::SOURCE_TRAJECTORY || source_ == Status_t::SOURCE_STOPPING) {
    return Refuse("IIWA_COMMAND", "IIWA_COMMAND ignored: the driver is " + SourceName(source_));
  }
  if (source_ == Status_t::SOURCE_HOLD) {
    if (const std::string far = FarFromCurrent(q); !far.empty()) {
      return Refuse("IIWA_COMMAND", "IIWA_COMMAND stream " + far);
    }
    source_ = Status_t::SOURCE_STREAM;
    trajectory_id_.clear();
    stream_.clear();
    Emit(Status_t::EVENT_ACCEPTED, "following IIWA_COMMAND");
  }
  if (stream_.size() == kStreamPoints) stream_.erase(stream_.begin());
  if (!stream_.empty() && host_us <= stream_.back().host_us) {
    stream_.back().position = q;  // two in the same microsecond: the newer wins
  } else {
    stream_.push_back({host_us, q});
  }
  stream_host_us_ = host_us;
}

void IiwaSession::StreamTarget(std::int64_t host_us, Eigen::VectorXd& target,
                               Eigen::VectorXd& velocity) const {
  velocity = Eigen::VectorXd::Zero(n_);
  target = stream_.back().position;
  if (stream_.size() < 2) return;
  // One stream period late (the latest interval, within [1, 50] ms).
  const std::int64_t period = std::clamp<std::int64_t>(
      stream_.back().host_us - stream_[stream_.size() - 2].host_us, 1000, 50000);
  const std::int64_t t = host_us - period;
  if (t >= stream_.back().host_us) return;  // past the newest setpoint: hold it
  for (std::size_t k = stream_.size() - 1; k > 0; --k) {
    const StreamPoint& a = stream_[k - 1];
    const StreamPoint& b = stream_[k];
    if (t < a.host_us && k > 1) continue;
    const double span = static_cast<double>(b.host_us - a.host_us);
    const double f = std::clamp(static_cast<double>(t - a.host_us) / span, 0.0, 1.0);
    target = a.position + f * (b.position - a.position);
    if (f > 0.0 && f < 1.0) velocity = (b.position - a.position) / (span * 1e-6);
    return;
  }
}

void IiwaSession::CheckSilence(std::int64_t host_us) {
  now_host_us_ = std::max(now_host_us_, host_us);
  if (session_state_ < 0 || last_rx_host_us_ < 0) return;
  if (host_us - last_rx_host_us_ > static_cast<std::int64_t>(options_.silence_s * 1e6)) {
    if (source_ != Status_t::SOURCE_NONE && source_ != Status_t::SOURCE_HOLD) {
      Emit(Status_t::EVENT_STOPPED, "controller silent: motion aborted");
    }
    session_state_ = -1;
    quality_ = -1;
    source_ = Status_t::SOURCE_NONE;
    trajectory_.reset();
    sequence_.Reset();
    Emit(Status_t::EVENT_SESSION,
         "controller silent for more than " + std::to_string(options_.silence_s) + " s");
  }
}

Eigen::VectorXd IiwaSession::Brake(double dt) {
  for (Eigen::Index i = 0; i < n_; ++i) {
    const double v = commanded_velocity_[i];
    const double dv = options_.limits.max_acceleration[i] * dt;
    // Trapezoidal integration of the braking velocity.
    commanded_velocity_[i] = std::abs(v) <= dv ? 0.0 : v - std::copysign(dv, v);
  }
  return commanded_ + commanded_velocity_ * dt;
}

Eigen::VectorXd IiwaSession::Command(std::int64_t device_us, std::int64_t host_us, double dt) {
  Eigen::VectorXd q = hold_;
  switch (source_) {
    case Status_t::SOURCE_TRAJECTORY: {
      if (trajectory_start_device_us_ < 0) trajectory_start_device_us_ = device_us;
      const double t = static_cast<double>(device_us - trajectory_start_device_us_) * 1e-6;
      trajectory_time_ = t;
      const double fade = options_.blend_s > 0 ? std::max(0.0, 1.0 - t / options_.blend_s) : 0.0;
      q = trajectory_->Evaluate(t).position + fade * start_offset_;
      if (t >= trajectory_->duration()) {
        q = trajectory_->back().position;
        hold_ = q;
        source_ = Status_t::SOURCE_HOLD;
        Emit(Status_t::EVENT_COMPLETED, "completed");
        trajectory_.reset();
      }
      break;
    }
    case Status_t::SOURCE_STREAM: {
      if (host_us - stream_host_us_ > static_cast<std::int64_t>(options_.command_expire_s * 1e6)) {
        StartStopping("IIWA_COMMAND setpoints expired (none for " +
                      std::to_string(options_.command_expire_s) + " s): stopping");
        q = Brake(dt);
        break;
      }
      // Follow the interpolated stream: its velocity plus a correction of the remaining error
      // that can always brake in time (|correction| <= sqrt(2 a |error|)), within the velocity
      // and acceleration limits. A stream that jumps or stops abruptly is thus smoothed, never
      // passed on.
      Eigen::VectorXd target, target_velocity;
      StreamTarget(host_us, target, target_velocity);
      q = commanded_;
      for (Eigen::Index i = 0; i < n_; ++i) {
        const double e = target[i] - commanded_[i];
        const double a = options_.limits.max_acceleration[i];
        const double brake = std::sqrt(2 * a * std::abs(e));
        double v = target_velocity[i] + std::clamp(e / dt - target_velocity[i], -brake, brake);
        v = std::clamp(v, -options_.limits.max_velocity[i], options_.limits.max_velocity[i]);
        v = std::clamp(v, commanded_velocity_[i] - a * dt, commanded_velocity_[i] + a * dt);
        q[i] = commanded_[i] + v * dt;
      }
      break;
    }
    case Status_t::SOURCE_STOPPING: {
      q = Brake(dt);
      if (commanded_velocity_.isZero(0)) {
        source_ = Status_t::SOURCE_HOLD;
        hold_ = q;
      }
      break;
    }
    default:
      break;
  }
  // Last guard for every source: position and velocity limits. 1 % of margin: a time-optimal
  // trajectory runs at the limit, and the start-offset blend adds up to
  // start_tolerance / blend_s on top (2 mrad/s with the defaults).
  bool limited = false;
  for (Eigen::Index i = 0; i < n_; ++i) {
    const double step = options_.limits.max_velocity[i] * 1.01 * dt;
    const double clamped = std::clamp(std::clamp(q[i], commanded_[i] - step, commanded_[i] + step),
                                      options_.limits.lower[i], options_.limits.upper[i]);
    limited = limited || std::abs(clamped - q[i]) > 1e-12;
    q[i] = clamped;
  }
  if (limited) ++limited_cycles_;
  if (source_ != Status_t::SOURCE_STOPPING) commanded_velocity_ = (q - commanded_) / dt;
  if (source_ == Status_t::SOURCE_STREAM || source_ == Status_t::SOURCE_TRAJECTORY) hold_ = q;
  return q;
}

void IiwaSession::OnSessionState(int state) {
  if (state == session_state_) return;
  if (session_state_ == kActive &&
      (source_ == Status_t::SOURCE_TRAJECTORY || source_ == Status_t::SOURCE_STREAM ||
       source_ == Status_t::SOURCE_STOPPING)) {
    Emit(Status_t::EVENT_STOPPED, std::string("session left COMMANDING_ACTIVE for ") +
                                      fri::ToString(static_cast<fri::SessionState>(state)) +
                                      ": motion aborted");
    trajectory_.reset();
  }
  session_state_ = state;
  multiplier_counter_ = 0;
  if (state != kActive) source_ = Status_t::SOURCE_NONE;
  Emit(Status_t::EVENT_SESSION, fri::ToString(static_cast<fri::SessionState>(state)));
}

std::optional<fri::CommandData> IiwaSession::CommandFor(const fri::MonitoringMessage& m, int state,
                                                        std::int64_t device_us,
                                                        std::int64_t host_us, double dt) {
  // The position the controller interpolates: our starting point for commanding.
  Eigen::VectorXd ipo = measured_;
  if (m.ipo_data && m.ipo_data->joint_position &&
      static_cast<Eigen::Index>(m.ipo_data->joint_position->size()) == n_) {
    ipo = Eigen::Map<const Eigen::VectorXd>(m.ipo_data->joint_position->data(), n_);
  }
  fri::CommandData command;
  if (state == kWait) {
    // Echo the interpolator's position, as the SDK's default waitForCommand() does.
    commanded_ = hold_ = ipo;
    commanded_velocity_.setZero();
    have_commanded_ = true;
    command.joint_position = fri::JointValues(ipo.data(), ipo.data() + n_);
    return command;
  }
  if (state != kActive) {
    have_commanded_ = false;
    return std::nullopt;
  }
  if (source_ == Status_t::SOURCE_NONE) {
    source_ = Status_t::SOURCE_HOLD;
    commanded_ = hold_ = have_commanded_ ? commanded_ : ipo;
    commanded_velocity_.setZero();
    have_commanded_ = true;
  }
  const Eigen::VectorXd q = Command(device_us, host_us, dt);
  commanded_ = q;
  command.joint_position = fri::JointValues(q.data(), q.data() + n_);
  return command;
}

std::optional<fri::CommandMessage> IiwaSession::OnMonitoring(const fri::MonitoringMessage& m,
                                                             std::int64_t host_us,
                                                             std::string* error) {
  now_host_us_ = std::max(now_host_us_, host_us);
  if (const std::string problem = MonitoringProblem(m, n_); !problem.empty()) {
    if (error) *error = problem;
    return std::nullopt;
  }
  // Sequence: count gaps, ignore what arrives after a newer message.
  const std::uint32_t sequence = m.header.sequence_counter;
  const timing::CounterStep step = sequence_.Update(sequence);
  if (step.repeated() || step.went_backwards()) {
    ++late_;
    return std::nullopt;
  }
  lost_ += step.lost;
  ++received_;
  last_rx_host_us_ = host_us;
  const std::int64_t device_us = DeviceUs(m, host_us);
  const double dt =
      last_device_us_ < 0
          ? 0.005
          : std::clamp(static_cast<double>(device_us - last_device_us_) * 1e-6, 1e-4, 0.1);
  last_device_us_ = device_us;
  measured_ =
      Eigen::Map<const Eigen::VectorXd>(m.monitor_data->measured_joint_position->data(), n_);

  const int state = static_cast<int>(m.connection_info->session_state);
  quality_ = static_cast<int>(m.connection_info->quality);
  OnSessionState(state);
  if (state == static_cast<int>(fri::SessionState::kIdle)) return std::nullopt;
  fri::CommandMessage reply;
  reply.header = {fri::kCommandMessageId, 0, sequence};
  reply.command_data = CommandFor(m, state, device_us, host_us, dt);
  const std::uint32_t multiplier =
      std::max<std::uint32_t>(1, m.connection_info->receive_multiplier.value_or(1));
  if (++multiplier_counter_ % multiplier != 0) return std::nullopt;
  reply.header.sequence_counter = own_sequence_++;
  ++replies_;
  return reply;
}

}  // namespace selfcal::iiwa
