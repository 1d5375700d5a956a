#include "drivers/iiwa/iiwa_driver.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>
#include <limits>

#include "core/timing/host_clock.h"
#include "core/util/printable.h"
#include "drake/lcmt_iiwa_command.hpp"
#include "protocols/fri/fri_codec.h"
#include "protocols/lcm_log/lcm_codec.h"
#include "selfcal/joint_trajectory_t.hpp"

namespace selfcal::iiwa {

namespace {

SessionOptions FillSession(SessionOptions session, const RobotModel& model) {
  session.joint_names.clear();
  for (const JointSpec& joint : model.joints) session.joint_names.push_back(joint.name);
  session.limits = trajectory::LimitsFromModel(model);
  return session;
}

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

IiwaDriver::IiwaDriver(DriverOptions options, Bus& bus, LogSink log)
    : options_(std::move(options)),
      bus_(bus),
      session_(FillSession(options_.session, options_.model)),
      clock_(options_.clock),
      verifier_(options_.key, timing::RealtimeUs()),
      log_(log ? std::move(log) : [](LogLevel, const std::string&) {}) {
  const auto n = static_cast<int>(options_.model.JointCount());
  receive_buffer_.resize(fri::kMaxMessageBytes + 1);
  send_buffer_.resize(fri::kMaxMessageBytes);
  joint_state_.num_joints = n;
  for (const JointSpec& joint : options_.model.joints) joint_state_.names.push_back(joint.name);
  joint_state_.positions.resize(static_cast<std::size_t>(n));
  joint_state_.velocities.resize(static_cast<std::size_t>(n));
  joint_state_.efforts.resize(static_cast<std::size_t>(n));
  iiwa_status_.num_joints = n;
  for (auto* v : {&iiwa_status_.joint_position_measured, &iiwa_status_.joint_velocity_estimated,
                  &iiwa_status_.joint_position_commanded, &iiwa_status_.joint_position_ipo,
                  &iiwa_status_.joint_torque_measured, &iiwa_status_.joint_torque_commanded,
                  &iiwa_status_.joint_torque_external}) {
    v->assign(static_cast<std::size_t>(n), kNaN);
  }
  previous_measured_ = velocity_ = Eigen::VectorXd::Zero(n);
}

IiwaDriver::~IiwaDriver() {
  if (socket_ >= 0) ::close(socket_);
}

Expected<std::unique_ptr<IiwaDriver>> IiwaDriver::Create(DriverOptions options, Bus& bus,
                                                         LogSink log) {
  if (options.model.joints.empty()) return Error{"selfcal-iiwa: the robot model has no joints"};
  if (options.model.JointCount() > fri::kMaxJointValues) {
    return Error{"selfcal-iiwa: more than 32 joints"};
  }
  std::unique_ptr<IiwaDriver> driver(new IiwaDriver(std::move(options), bus, std::move(log)));
  const DriverOptions& o = driver->options_;
  driver->socket_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (driver->socket_ < 0) return Error{std::string("FRI socket: ") + std::strerror(errno)};
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(o.fri_port);
  if (::inet_pton(AF_INET, o.bind_host.c_str(), &address.sin_addr) != 1) {
    return Error{"FRI bind host '" + o.bind_host + "' is not an IPv4 address"};
  }
  if (::bind(driver->socket_, reinterpret_cast<sockaddr*>(&address), sizeof(address)) != 0) {
    return Error{"cannot bind FRI port " + o.bind_host + ":" + std::to_string(o.fri_port) + ": " +
                 std::strerror(errno)};
  }
  socklen_t length = sizeof(address);
  ::getsockname(driver->socket_, reinterpret_cast<sockaddr*>(&address), &length);
  driver->port_ = ntohs(address.sin_port);

  IiwaDriver* self = driver.get();
  bus.Subscribe(o.trajectory_channel, [self](const BusMessage& message) {
    auto decoded = DecodeLcm<selfcal::joint_trajectory_t>(message.data, message.channel);
    if (!decoded.ok()) {
      self->PublishStatus(selfcal::robot_driver_status_t::EVENT_REFUSED, "",
                          decoded.error().message, timing::RealtimeUs());
      return;
    }
    self->OnTrajectory(*decoded);
  });
  bus.Subscribe(o.iiwa_command_channel, [self](const BusMessage& message) {
    if (!self->options_.follow_iiwa_command) {
      const std::int64_t now = timing::RealtimeUs();
      self->session_.Refuse(
          "IIWA_COMMAND", "IIWA_COMMAND ignored: following it is off (--follow-iiwa-command)", now);
      self->PublishEvents(now);
      return;
    }
    auto decoded = DecodeLcm<drake::lcmt_iiwa_command>(message.data, message.channel);
    const std::int64_t now = timing::RealtimeUs();
    if (!decoded.ok()) {
      self->PublishStatus(selfcal::robot_driver_status_t::EVENT_REFUSED, "IIWA_COMMAND",
                          decoded.error().message, now);
      return;
    }
    self->session_.OnStreamCommand(*decoded, now);
    self->PublishEvents(now);
  });
  return driver;
}

void IiwaDriver::OnTrajectory(const selfcal::joint_trajectory_t& message) {
  const std::int64_t now = timing::RealtimeUs();
  const std::string id = Printable(message.trajectory_id);
  if (message.num_points == 0) {
    // A stop cannot move the arm, and stopping must never depend on a key.
    if (!verifier_.Authentic(message)) {
      log_.Log(LogLevel::kInfo, "unsigned stop",
               "honouring a stop request '" + id + "' that is not signed with the key");
    }
    session_.OnTrajectory(message, now);
  } else if (const std::string refused =
                 verifier_.Check(message, now, static_cast<std::int64_t>(timing::MonotonicUs()));
             !refused.empty()) {
    log_.Log(LogLevel::kWarning, refused, "trajectory '" + id + "' refused: " + refused);
    session_.Refuse(message.trajectory_id, refused, now);
  } else {
    session_.OnTrajectory(message, now);
  }
  PublishEvents(now);
}

void IiwaDriver::PublishStatus(std::int8_t event, const std::string& trajectory_id,
                               const std::string& message, std::int64_t host_us) {
  selfcal::robot_driver_status_t status;
  status.utime = host_us;
  status.session_state = static_cast<std::int8_t>(session_.session_state());
  status.connection_quality = static_cast<std::int8_t>(session_.quality());
  status.command_source = session_.command_source();
  status.event = event;
  status.trajectory_id = trajectory_id.empty() ? session_.trajectory_id() : trajectory_id;
  status.trajectory_time = session_.trajectory_time();
  status.messages_received = session_.messages_received();
  status.messages_lost = session_.messages_lost();
  status.messages_late = session_.messages_late();
  status.decode_errors = decode_errors_;
  status.replies_sent = session_.replies_sent();
  status.clock_settled = clock_.settled();
  status.clock_drift_ppm = clock_.drift_ppm();
  status.message = message.empty() ? "ok" : message;
  (void)bus_.Publish(options_.status_channel, status);
  last_status_host_us_ = host_us;
}

void IiwaDriver::PublishEvents(std::int64_t host_us) {
  for (const SessionEvent& e : session_.TakeEvents()) {
    PublishStatus(e.event, e.trajectory_id, e.message, host_us);
  }
}

void IiwaDriver::HandleDatagram(std::span<const std::uint8_t> bytes, std::int64_t host_us) {
  auto message = fri::DecodeMonitoringMessage(bytes);
  std::string error;
  std::optional<fri::CommandMessage> reply;
  if (message.ok()) {
    reply = session_.OnMonitoring(*message, host_us, &error);
  } else {
    error = message.error().message;
  }
  if (!error.empty()) {
    ++decode_errors_;
    // Once per distinct reason, so a flood of garbage cannot flood the bus.
    if (error != last_decode_error_) {
      last_decode_error_ = error;
      PublishStatus(selfcal::robot_driver_status_t::EVENT_PERIODIC, "",
                    "bad FRI datagram: " + error, host_us);
    }
    return;
  }
  if (reply) {
    auto size = fri::EncodeCommandMessage(*reply, send_buffer_);
    if (size.ok()) {
      ::sendto(socket_, send_buffer_.data(), *size, 0, reinterpret_cast<sockaddr*>(sender_),
               sender_length_);
    }
  }
  PublishEvents(host_us);
  const auto& m = *message;
  if (!m.monitor_data || !m.monitor_data->timestamp) return;
  const std::int64_t device_us =
      static_cast<std::int64_t>(m.monitor_data->timestamp->sec) * 1000000 +
      m.monitor_data->timestamp->nanosec / 1000;
  // A late message (the session ignored it) is older than what we published: skip it too.
  if (device_us <= previous_device_us_) return;
  if (const timing::ClockJump jump = clock_.Add(device_us, host_us);
      jump != timing::ClockJump::kNone) {
    PublishStatus(
        selfcal::robot_driver_status_t::EVENT_PERIODIC, "",
        "controller clock " + std::string(timing::ToString(jump)) + ": clock mapping restarted",
        host_us);
  }
  const Eigen::VectorXd measured = session_.measured();
  if (previous_device_us_ >= 0) {
    const double dt = static_cast<double>(device_us - previous_device_us_) * 1e-6;
    const double rc = 1.0 / (2 * M_PI * options_.velocity_filter_cutoff_hz);
    const double alpha = dt / (dt + rc);
    velocity_ += alpha * ((measured - previous_measured_) / dt - velocity_);
  }
  previous_device_us_ = device_us;
  previous_measured_ = measured;
  if (!clock_.settled()) return;  // host time not trustworthy yet: publish nothing
  PublishState(m, device_us, measured);
}

void IiwaDriver::PublishState(const fri::MonitoringMessage& m, std::int64_t device_us,
                              const Eigen::VectorXd& measured) {
  const auto n = static_cast<Eigen::Index>(options_.model.JointCount());
  const std::int64_t utime = clock_.ToHost(device_us);
  const auto& d = *m.monitor_data;
  joint_state_.utime = utime;
  joint_state_.device_utime = device_us;
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    joint_state_.positions[k] = measured[i];
    joint_state_.velocities[k] = velocity_[i];
    joint_state_.efforts[k] =
        d.measured_torque && k < d.measured_torque->size() ? (*d.measured_torque)[k] : kNaN;
  }
  (void)bus_.Publish(options_.joint_state_channel, joint_state_);

  iiwa_status_.utime = utime;
  const bool commanding = session_.session_state() == 3 || session_.session_state() == 4;
  auto copy = [&](std::vector<double>& out, const std::optional<fri::JointValues>& in) {
    for (std::size_t k = 0; k < out.size(); ++k) {
      out[k] = in && in->size() == out.size() ? (*in)[k] : kNaN;
    }
  };
  copy(iiwa_status_.joint_position_measured, d.measured_joint_position);
  for (Eigen::Index i = 0; i < n; ++i) {
    iiwa_status_.joint_velocity_estimated[static_cast<std::size_t>(i)] = velocity_[i];
  }
  copy(iiwa_status_.joint_position_commanded, d.commanded_joint_position);
  if (commanding && m.ipo_data) {
    copy(iiwa_status_.joint_position_ipo, m.ipo_data->joint_position);
  } else {
    copy(iiwa_status_.joint_position_ipo, std::nullopt);  // Drake: NaN in monitoring mode
  }
  copy(iiwa_status_.joint_torque_measured, d.measured_torque);
  copy(iiwa_status_.joint_torque_commanded, d.commanded_torque);
  copy(iiwa_status_.joint_torque_external, d.external_torque);
  (void)bus_.Publish(options_.iiwa_status_channel, iiwa_status_);
  ++published_;
}

Status IiwaDriver::SpinOnce(std::chrono::microseconds timeout) {
  pollfd fds[2] = {{socket_, POLLIN, 0}, {bus_.FileDescriptor(), POLLIN, 0}};
  timespec ts{static_cast<time_t>(timeout.count() / 1000000),
              static_cast<long>((timeout.count() % 1000000) * 1000)};
  const int ready = ::ppoll(fds, 2, &ts, nullptr);
  if (ready < 0 && errno != EINTR) return Error{std::string("poll: ") + std::strerror(errno)};
  if (ready > 0 && (fds[0].revents & POLLIN)) {
    while (true) {
      sockaddr_storage from{};
      socklen_t from_length = sizeof(from);
      const ssize_t n = ::recvfrom(socket_, receive_buffer_.data(), receive_buffer_.size(), 0,
                                   reinterpret_cast<sockaddr*>(&from), &from_length);
      if (n < 0) break;
      const std::int64_t host_us = timing::RealtimeUs();
      if (from_length <= sizeof(sender_)) {
        std::memcpy(sender_, &from, from_length);
        sender_length_ = from_length;
      }
      HandleDatagram({receive_buffer_.data(), static_cast<std::size_t>(n)}, host_us);
    }
  }
  if (ready > 0 && (fds[1].revents & POLLIN)) {
    for (int i = 0; i < 100; ++i) {
      auto handled = bus_.HandleOnce(std::chrono::milliseconds(0));
      if (!handled.ok()) return handled.error();
      if (!*handled) break;
    }
  }
  const std::int64_t now = timing::RealtimeUs();
  session_.CheckSilence(now);
  PublishEvents(now);
  log_.Flush();
  if (now - last_status_host_us_ >= static_cast<std::int64_t>(options_.status_period_s * 1e6)) {
    PublishStatus(selfcal::robot_driver_status_t::EVENT_PERIODIC, "", "", now);
  }
  return OkStatus();
}

}  // namespace selfcal::iiwa
