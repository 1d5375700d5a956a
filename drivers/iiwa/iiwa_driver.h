// selfcal-iiwa: the FRI client on UDP. Receives monitoring messages on its port (30200 by
// default), answers through IiwaSession, maps the controller clock to host time with a
// ClockFilter, and publishes over the bus:
//   SELFCAL_JOINT_STATE  selfcal.joint_state_t   every monitoring message, once the clock settled
//   IIWA_STATUS          drake.lcmt_iiwa_status  the same instants, Drake's type and fields
//   SELFCAL_ROBOT_STATUS selfcal.robot_driver_status_t  10 Hz and every event (refusals...)
// and executes SELFCAL_JOINT_TRAJECTORY (selfcal.joint_trajectory_t) when it is signed with the
// key (protocols/trajectory/trajectory_signature.h; stop requests need no signature). Follows
// IIWA_COMMAND (drake.lcmt_iiwa_command, unauthenticated) only when asked to.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/model/robot_model.h"
#include "core/timing/clock_filter.h"
#include "core/util/expected.h"
#include "core/util/log.h"
#include "drake/lcmt_iiwa_status.hpp"
#include "drivers/iiwa/iiwa_session.h"
#include "protocols/auth/key.h"
#include "protocols/bus/bus.h"
#include "protocols/lcm/channels.h"
#include "protocols/trajectory/trajectory_signature.h"
#include "selfcal/joint_state_t.hpp"

namespace selfcal::iiwa {

struct DriverOptions {
  std::string bind_host = "0.0.0.0";
  std::uint16_t fri_port = 30200;  // 0: any free port (tests)
  RobotModel model;
  std::string joint_state_channel = channels::kJointState;
  std::string iiwa_status_channel = channels::kIiwaStatus;
  std::string iiwa_command_channel = channels::kIiwaCommand;
  std::string trajectory_channel = channels::kJointTrajectory;
  std::string status_channel = channels::kRobotStatus;
  double velocity_filter_cutoff_hz = 40.0;  // Drake's default
  double status_period_s = 0.1;
  // The key every trajectory that moves the arm must be signed with; none: all are refused.
  std::optional<auth::Key> key;
  // Follow IIWA_COMMAND: Drake's stream has no authentication, so anyone who can send to the bus
  // can move the arm. Off: IIWA_COMMAND is refused unread.
  bool follow_iiwa_command = false;
  SessionOptions session;  // joint names and limits are filled from `model`
  // The controller's clock is a quartz that drifts by tens of ppm: a steeper line through the
  // receive times is a backlog read in a burst, not the clock.
  timing::ClockFilterOptions clock = [] {
    timing::ClockFilterOptions options;
    options.max_drift = 1e-3;
    return options;
  }();
};

class IiwaDriver {
 public:
  // Binds the FRI port and subscribes on `bus` (which must outlive the driver). Refused
  // trajectories and unsigned stops are logged to `log` (rate-limited).
  static Expected<std::unique_ptr<IiwaDriver>> Create(DriverOptions options, Bus& bus,
                                                      LogSink log = {});
  ~IiwaDriver();

  std::uint16_t port() const { return port_; }
  // Waits up to `timeout` for FRI datagrams and LCM messages and handles all that arrived.
  Status SpinOnce(std::chrono::microseconds timeout);

  const IiwaSession& session() const { return session_; }
  const timing::ClockFilter& clock() const { return clock_; }
  std::int64_t decode_errors() const { return decode_errors_; }
  std::int64_t published_joint_states() const { return published_; }

 private:
  IiwaDriver(DriverOptions options, Bus& bus, LogSink log);
  // A decoded joint_trajectory_t: a stop is honoured, anything else only when verified.
  void OnTrajectory(const selfcal::joint_trajectory_t& message);
  void HandleDatagram(std::span<const std::uint8_t> bytes, std::int64_t host_us);
  // The joint state and Drake's iiwa status of a monitoring message, at host time.
  void PublishState(const fri::MonitoringMessage& m, std::int64_t device_us,
                    const Eigen::VectorXd& measured);
  void PublishStatus(std::int8_t event, const std::string& trajectory_id,
                     const std::string& message, std::int64_t host_us);
  void PublishEvents(std::int64_t host_us);

  DriverOptions options_;
  Bus& bus_;
  IiwaSession session_;
  timing::ClockFilter clock_;
  TrajectoryVerifier verifier_;
  RateLimitedLog log_;
  int socket_ = -1;
  std::uint16_t port_ = 0;
  std::int64_t decode_errors_ = 0;
  std::int64_t published_ = 0;
  std::int64_t last_status_host_us_ = 0;
  std::string last_decode_error_;
  // Sender of the last monitoring message: replies go there.
  std::vector<std::uint8_t> receive_buffer_, send_buffer_;
  std::uint8_t sender_[128] = {};
  unsigned sender_length_ = 0;
  // Preallocated messages and velocity filter state.
  selfcal::joint_state_t joint_state_;
  drake::lcmt_iiwa_status iiwa_status_;
  Eigen::VectorXd previous_measured_, velocity_;
  std::int64_t previous_device_us_ = -1;
};

}  // namespace selfcal::iiwa
