#include "tools/sim_fri/fri_simulator.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>

#include "core/timing/host_clock.h"
#include "protocols/fri/fri_codec.h"

namespace selfcal::sim {
namespace {

using timing::MonotonicNs;
using timing::RealtimeUs;

constexpr std::size_t kMaxSamples = 60 * 1000;

}  // namespace

Expected<std::unique_ptr<FriSimulator>> FriSimulator::Create(const FriSimOptions& options) {
  if (options.model.joints.empty()) return Error{"FRI simulator: the robot model has no joints"};
  if (!(options.period_s >= 0.001 && options.period_s <= 0.1)) {
    return Error{"FRI simulator: period must be within [0.001, 0.1] s"};
  }
  if (options.receive_multiplier < 1) return Error{"FRI simulator: receive multiplier >= 1"};
  const auto n = static_cast<Eigen::Index>(options.model.JointCount());
  if (options.initial_position.size() != 0 && options.initial_position.size() != n) {
    return Error{"FRI simulator: initial position has " +
                 std::to_string(options.initial_position.size()) + " values, the model " +
                 std::to_string(n) + " joints"};
  }
  std::unique_ptr<FriSimulator> sim(new FriSimulator(options));
  sim->socket_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (sim->socket_ < 0) return Error{std::string("FRI simulator: socket: ") + std::strerror(errno)};
  sockaddr_in local{};
  local.sin_family = AF_INET;
  local.sin_port = 0;
  if (::inet_pton(AF_INET, options.client_host.c_str(), &local.sin_addr) != 1) {
    return Error{"FRI simulator: client host '" + options.client_host + "' is not an IPv4 address"};
  }
  // Bind on the client's address family and host (loopback in tests), any port.
  if (::bind(sim->socket_, reinterpret_cast<sockaddr*>(&local), sizeof(local)) != 0) {
    return Error{std::string("FRI simulator: bind: ") + std::strerror(errno)};
  }
  socklen_t length = sizeof(local);
  ::getsockname(sim->socket_, reinterpret_cast<sockaddr*>(&local), &length);
  sim->local_port_ = ntohs(local.sin_port);
  sockaddr_in client{};
  client.sin_family = AF_INET;
  client.sin_port = htons(options.client_port);
  ::inet_pton(AF_INET, options.client_host.c_str(), &client.sin_addr);
  if (::connect(sim->socket_, reinterpret_cast<sockaddr*>(&client), sizeof(client)) != 0) {
    return Error{std::string("FRI simulator: connect: ") + std::strerror(errno)};
  }
  return sim;
}

void AdvanceServo(double bandwidth_hz, double interval_s, const Eigen::VectorXd& commanded,
                  const Eigen::VectorXd& feed_forward, Eigen::VectorXd& position,
                  Eigen::VectorXd& velocity) {
  const double w = 2 * M_PI * bandwidth_hz;
  constexpr double kMaxStep = 0.05;  // w h: well inside the stability bound of 0.83 (header)
  const int substeps = std::max(10, static_cast<int>(std::ceil(w * interval_s / kMaxStep)));
  const double h = interval_s / substeps;
  const Eigen::VectorXd ramp_start = commanded - feed_forward * interval_s;
  for (int k = 0; k < substeps; ++k) {
    const double fraction = static_cast<double>(k + 1) / substeps;
    const Eigen::VectorXd reference = ramp_start + fraction * (commanded - ramp_start);
    const Eigen::VectorXd acceleration =
        w * w * (reference - position) + 2 * w * (feed_forward - velocity);
    velocity += h * acceleration;
    position += h * velocity;
  }
}

FriSimulator::FriSimulator(const FriSimOptions& options)
    : options_(options), random_(options.seed) {
  const auto n = static_cast<Eigen::Index>(options.model.JointCount());
  true_position_ =
      options.initial_position.size() == n ? options.initial_position : Eigen::VectorXd::Zero(n);
  true_velocity_ = Eigen::VectorXd::Zero(n);
  feed_forward_ = Eigen::VectorXd::Zero(n);
  commanded_ = previous_commanded_ = true_position_;
  answered_.assign(static_cast<std::size_t>(std::max(1, options.quality_window)), false);
  outgoing_.reserve(64);
  samples_.reserve(4096);
}

FriSimulator::~FriSimulator() {
  Stop();
  if (socket_ >= 0) ::close(socket_);
}

void FriSimulator::Start() {
  if (running_.exchange(true)) return;
  start_host_us_ = RealtimeUs();
  start_controller_us_ = static_cast<std::int64_t>(options_.clock_offset_s * 1e6);
  thread_ = std::thread([this] { Loop(); });
}

void FriSimulator::Stop() {
  if (!running_.exchange(false)) return;
  if (thread_.joinable()) thread_.join();
}

fri::SessionState FriSimulator::state() const {
  std::lock_guard lock(mutex_);
  return state_;
}
fri::ConnectionQuality FriSimulator::quality() const {
  std::lock_guard lock(mutex_);
  return quality_;
}
FriSimStats FriSimulator::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}
void FriSimulator::RequestCommanding(bool on) {
  std::lock_guard lock(mutex_);
  commanding_requested_ = on;
}
void FriSimulator::SetLoss(double probability) {
  std::lock_guard lock(mutex_);
  options_.loss_probability = probability;
}
void FriSimulator::SetDelay(double probability, double delay_s) {
  std::lock_guard lock(mutex_);
  options_.delay_probability = probability;
  options_.delay_s = delay_s;
}
Eigen::VectorXd FriSimulator::TruePosition() const {
  std::lock_guard lock(mutex_);
  return true_position_;
}
std::vector<FriSimSample> FriSimulator::TakeSamples() {
  std::lock_guard lock(mutex_);
  std::vector<FriSimSample> taken;
  taken.swap(samples_);
  samples_.reserve(4096);
  return taken;
}

std::int64_t FriSimulator::ControllerToHostUs(std::int64_t controller_us) const {
  const long double elapsed = static_cast<long double>(controller_us - start_controller_us_) /
                              (1.0L + static_cast<long double>(options_.drift_ppm) * 1e-6L);
  return start_host_us_ + static_cast<std::int64_t>(std::llround(elapsed));
}

void FriSimulator::Loop() {
  // Wake up on time: the default 50 us timer slack would show as transmission delay.
  ::prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  const auto period_ns = static_cast<std::int64_t>(options_.period_s * 1e9);
  std::int64_t next_cycle = MonotonicNs();
  while (running_.load()) {
    const std::int64_t now = MonotonicNs();
    if (now >= next_cycle) {
      // The sample instant is when this cycle actually runs (a loaded machine makes it late):
      // the controller clock is read then, so the truth stays exact; the simulator's checks use
      // these stamps, not the nominal period.
      {
        std::lock_guard lock(mutex_);
        Cycle(RealtimeUs());
      }
      next_cycle += period_ns;
      // Running late (a loaded machine): the next cycle comes at least half a period later,
      // never in a burst of back-to-back cycles.
      next_cycle = std::max(next_cycle, MonotonicNs() + period_ns / 2);
    }
    std::int64_t wake = next_cycle;
    {
      std::lock_guard lock(mutex_);
      SendDue(RealtimeUs(), false);
      for (const Outgoing& o : outgoing_) {
        const std::int64_t due_mono = MonotonicNs() + (o.due_host_us - RealtimeUs()) * 1000;
        wake = std::min(wake, due_mono);
      }
    }
    const std::int64_t wait_ns = std::max<std::int64_t>(0, wake - MonotonicNs());
    pollfd fd{socket_, POLLIN, 0};
    timespec timeout{static_cast<time_t>(wait_ns / 1000000000),
                     static_cast<long>(wait_ns % 1000000000)};
    if (::ppoll(&fd, 1, &timeout, nullptr) > 0) {
      std::lock_guard lock(mutex_);
      ReceiveReplies();
    }
  }
  std::lock_guard lock(mutex_);
  SendDue(RealtimeUs(), true);
}

void FriSimulator::ReceiveReplies() {
  std::uint8_t buffer[fri::kMaxMessageBytes + 1];
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  while (true) {
    const ssize_t n = ::recv(socket_, buffer, sizeof(buffer), 0);
    if (n < 0) return;  // EAGAIN, or ECONNREFUSED while no client listens
    if (options_.loss_probability > 0 && uniform(random_) < options_.loss_probability) {
      ++stats_.replies_dropped;
      continue;
    }
    auto reply = fri::DecodeCommandMessage({buffer, static_cast<std::size_t>(n)});
    if (!reply.ok() || reply->header.message_identifier != fri::kCommandMessageId) {
      ++stats_.decode_errors;
      continue;
    }
    ++stats_.replies;
    if (state_ == fri::SessionState::kIdle) ++stats_.replies_in_idle;
    const std::uint32_t last_sent = sequence_ - 1;
    if (reply->header.reflected_sequence_counter != last_sent) {
      if (reply->header.reflected_sequence_counter < last_sent) {
        ++stats_.late_replies;
      } else {
        ++stats_.wrong_reflection;
      }
      continue;
    }
    answered_this_cycle_ = true;
    const auto& data = reply->command_data;
    if (data && data->joint_position &&
        data->joint_position->size() == static_cast<std::size_t>(commanded_.size())) {
      Eigen::VectorXd q =
          Eigen::Map<const Eigen::VectorXd>(data->joint_position->data(), commanded_.size());
      if (q.allFinite()) {
        pending_echo_ok_ = (q - commanded_).cwiseAbs().maxCoeff() < 1e-9;
        pending_command_ = q;
      }
    }
  }
}

void FriSimulator::UpdateState() {
  using S = fri::SessionState;
  using Q = fri::ConnectionQuality;
  const S before = state_;
  const bool good = quality_ == Q::kGood || quality_ == Q::kExcellent;
  const double elapsed_s = static_cast<double>(stats_.cycles) * options_.period_s;
  // Automatic mode (the demo's robot application): command again each time the session is
  // ready, also after a lost session.
  if (options_.command_after_s >= 0 && state_ == S::kMonitoringReady &&
      cycles_in_state_ * options_.period_s >= options_.command_after_s) {
    commanding_requested_ = true;
  }
  (void)elapsed_s;
  switch (state_) {
    case S::kIdle:
      if (cycles_in_state_ >= options_.idle_cycles) state_ = S::kMonitoringWait;
      break;
    case S::kMonitoringWait:
      if (good && cycles_in_state_ >= options_.quality_window) state_ = S::kMonitoringReady;
      break;
    case S::kMonitoringReady:
      if (!good) {
        state_ = S::kMonitoringWait;
      } else if (commanding_requested_) {
        state_ = S::kCommandingWait;
        echo_cycles_ = 0;
      }
      break;
    case S::kCommandingWait:
      if (quality_ == Q::kPoor) {
        state_ = S::kMonitoringWait;
      } else if (!commanding_requested_) {
        state_ = S::kMonitoringReady;
      } else if (echo_cycles_ >= options_.commanding_wait_cycles) {
        state_ = S::kCommandingActive;
      }
      break;
    case S::kCommandingActive:
      if (quality_ == Q::kPoor) {
        state_ = S::kMonitoringWait;
        ++stats_.sessions_lost;
        commanding_requested_ = false;
      } else if (!commanding_requested_) {
        state_ = S::kMonitoringReady;
      }
      break;
  }
  if (state_ != before) cycles_in_state_ = 0;
}

void FriSimulator::Cycle(std::int64_t host_us) {
  using S = fri::SessionState;
  ++stats_.cycles;
  const auto n = commanded_.size();
  // 1. Was the previous message answered in time? (IDLE expects no answer.)
  if (state_ != S::kIdle) {
    answered_[answered_head_] = answered_this_cycle_;
    answered_head_ = (answered_head_ + 1) % answered_.size();
    const double share = static_cast<double>(std::count(answered_.begin(), answered_.end(), true)) /
                         static_cast<double>(answered_.size());
    quality_ = share >= 0.95  ? fri::ConnectionQuality::kExcellent
               : share >= 0.8 ? fri::ConnectionQuality::kGood
               : share >= 0.6 ? fri::ConnectionQuality::kFair
                              : fri::ConnectionQuality::kPoor;
  }
  // 2. The servo model over the period that just ended, following the command in effect: the
  // interpolator ramps from the previous setpoint to the new one over the period (as the
  // controller's IPO does), and the servo is critically damped with velocity feed-forward.
  {
    const double interval_s =
        previous_cycle_host_us_ < 0
            ? options_.period_s
            : std::clamp(static_cast<double>(host_us - previous_cycle_host_us_) * 1e-6, 0.0, 0.1);
    previous_cycle_host_us_ = host_us;
    AdvanceServo(options_.servo_bandwidth_hz, interval_s, commanded_, feed_forward_, true_position_,
                 true_velocity_);
  }
  // 3. The commanded position of the reply to the previous message; in effect from now on.
  previous_commanded_ = commanded_;
  if (state_ == S::kCommandingWait) {
    echo_cycles_ = (pending_command_ && pending_echo_ok_) ? echo_cycles_ + 1 : 0;
  }
  bool command_received = false;
  if (state_ == S::kCommandingActive && pending_command_) {
    Eigen::VectorXd q = *pending_command_;
    double ratio = 0;
    // The reply answers the last message sent; the client moved its setpoint by the controller
    // time between that message and the one its previous setpoint answered.
    const double elapsed_s =
        last_command_stamp_us_ < 0
            ? options_.period_s
            : static_cast<double>(last_sent_stamp_us_ - last_command_stamp_us_) * 1e-6;
    for (Eigen::Index i = 0; i < n; ++i) {
      const double allowed = options_.model.joints[static_cast<std::size_t>(i)].max_velocity *
                             std::max(elapsed_s, 1e-4);
      const double step = q[i] - commanded_[i];
      ratio = std::max(ratio, std::abs(step) / allowed);
      if (std::abs(step) > allowed * 1.05) q[i] = commanded_[i] + std::copysign(allowed, step);
    }
    stats_.max_step_ratio = std::max(stats_.max_step_ratio, ratio);
    if (ratio > 1.05) ++stats_.velocity_violations;
    // Joint limits: the controller never leaves them.
    for (Eigen::Index i = 0; i < n; ++i) {
      const JointSpec& joint = options_.model.joints[static_cast<std::size_t>(i)];
      q[i] = std::clamp(q[i], joint.lower, joint.upper);
    }
    commanded_ = q;
    cycles_since_command_ = 1;
    command_received = true;
    feed_forward_ = (commanded_ - previous_commanded_) / std::max(elapsed_s, 1e-4);
    last_command_stamp_us_ = last_sent_stamp_us_;
  } else {
    ++cycles_since_command_;
    feed_forward_.setZero();  // the controller holds the last setpoint
  }
  pending_command_.reset();
  answered_this_cycle_ = false;
  ++cycles_in_state_;
  UpdateState();
  // 4. The monitoring message of this cycle: the state sampled at its start.
  const std::int64_t controller_us =
      start_controller_us_ +
      static_cast<std::int64_t>(std::llround(static_cast<long double>(host_us - start_host_us_) *
                                             (1.0L + options_.drift_ppm * 1e-6L)));
  std::normal_distribution<double> noise(0.0, options_.position_noise_rad);
  fri::MonitoringMessage m;
  m.header = {fri::kMonitorMessageId, sequence_++, 0};
  fri::RobotInfo info;
  info.number_of_joints = static_cast<std::int32_t>(n);
  info.safety_state = fri::SafetyState::kNormalOperation;
  info.drive_state.assign(static_cast<std::size_t>(n), fri::DriveState::kActive);
  info.operation_mode = fri::OperationMode::kAutomatic;
  info.control_mode = fri::ControlMode::kPosition;
  m.robot_info = info;
  fri::MonitorData d;
  fri::JointValues measured(static_cast<std::size_t>(n)), torque(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    measured[static_cast<std::size_t>(i)] = true_position_[i] + noise(random_);
    // A stand-in for gravity load: depends on the pose, distinct per joint.
    torque[static_cast<std::size_t>(i)] =
        10.0 * std::sin(true_position_[i]) / static_cast<double>(i + 1);
  }
  d.measured_joint_position = measured;
  d.measured_torque = torque;
  d.commanded_joint_position = fri::JointValues(commanded_.data(), commanded_.data() + n);
  d.commanded_torque = torque;
  d.external_torque = fri::JointValues(static_cast<std::size_t>(n), 0.0);
  d.timestamp = fri::TimeStamp{static_cast<std::uint32_t>(controller_us / 1000000),
                               static_cast<std::uint32_t>((controller_us % 1000000) * 1000)};
  m.monitor_data = d;
  m.connection_info = fri::ConnectionInfo{
      state_, quality_,
      static_cast<std::uint32_t>(std::max(1.0, std::round(options_.period_s * 1000))),
      options_.receive_multiplier};
  if (state_ == S::kCommandingWait || state_ == S::kCommandingActive) {
    fri::IpoData ipo;
    ipo.joint_position = fri::JointValues(commanded_.data(), commanded_.data() + n);
    ipo.client_command_mode = fri::ClientCommandMode::kPosition;
    ipo.overlay_type = fri::OverlayType::kJoint;
    ipo.tracking_performance = 1.0;
    m.ipo_data = ipo;
  }
  Outgoing out;
  out.bytes.resize(fri::kMaxMessageBytes);
  auto size = fri::EncodeMonitoringMessage(m, out.bytes);
  if (!size.ok()) return;  // cannot happen for <= 32 joints
  out.bytes.resize(*size);
  last_sent_stamp_us_ = controller_us;
  if (state_ != S::kCommandingActive) last_command_stamp_us_ = -1;
  if (samples_.size() < kMaxSamples) {
    samples_.push_back(
        {host_us, controller_us, state_, true_position_, commanded_, command_received});
  }
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  if (options_.loss_probability > 0 && uniform(random_) < options_.loss_probability) {
    ++stats_.dropped;
    return;
  }
  out.due_host_us = host_us;
  if (options_.delay_probability > 0 && uniform(random_) < options_.delay_probability) {
    out.due_host_us += static_cast<std::int64_t>(options_.delay_s * 1e6);
    ++stats_.delayed;
  }
  outgoing_.push_back(std::move(out));
  SendDue(host_us, false);
}

void FriSimulator::SendDue(std::int64_t now_host_us, bool flush_all) {
  // In order of due time: a delayed message goes out after the newer ones that overtook it,
  // even when this thread runs late and both are due at once.
  std::stable_sort(outgoing_.begin(), outgoing_.end(), [](const Outgoing& a, const Outgoing& b) {
    return a.due_host_us < b.due_host_us;
  });
  for (auto it = outgoing_.begin(); it != outgoing_.end();) {
    if (flush_all || it->due_host_us <= now_host_us) {
      if (!flush_all) {
        ::send(socket_, it->bytes.data(), it->bytes.size(), 0);
        ++stats_.sent;
      }
      it = outgoing_.erase(it);
    } else {
      ++it;
    }
  }
}

}  // namespace selfcal::sim
