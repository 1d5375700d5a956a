// The FRI client's logic without sockets: session states and reply rules, the command sources
// (hold, trajectory, Drake command stream, braking) and the safety checks. IiwaDriver feeds it
// decoded monitoring messages and LCM messages, sends its replies and publishes its events.
//
// Reply rules (../shared/protocols.md 3.2): IDLE -> no reply; MONITORING_WAIT/READY -> header
// only; COMMANDING_WAIT -> echo the IPO position; COMMANDING_ACTIVE -> the commanded position.
// A reply goes out for every receiveMultiplier-th message, with our own sequence counter and the
// monitoring message's counter reflected. Messages older than the newest seen are ignored.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/timing/counter_unwrapper.h"
#include "core/trajectory/joint_trajectory.h"
#include "drake/lcmt_iiwa_command.hpp"
#include "protocols/fri/fri_messages.h"
#include "selfcal/joint_trajectory_t.hpp"
#include "selfcal/robot_driver_status_t.hpp"

namespace selfcal::iiwa {

struct SessionOptions {
  std::vector<std::string> joint_names;  // from the robot model file
  trajectory::JointLimits limits;        // from the robot model file
  double start_tolerance_rad = 1e-3;     // a trajectory or stream must start this close
  double command_expire_s = 0.05;        // stream setpoints older than this stop the motion
  double blend_s = 0.5;                  // the start offset (<= tolerance) fades out over this
  double silence_s = 0.5;                // no monitoring message for this long: session lost
};

struct SessionEvent {
  std::int8_t event = 0;  // robot_driver_status_t::EVENT_*
  std::string trajectory_id;
  std::string message;
};

class IiwaSession {
 public:
  explicit IiwaSession(SessionOptions options);

  // A decoded monitoring message received at host time `host_us`. Returns the reply to send, if
  // any. `error` is set when the message was rejected (wrong identifier or joint count).
  std::optional<fri::CommandMessage> OnMonitoring(const fri::MonitoringMessage& message,
                                                  std::int64_t host_us, std::string* error);
  // A trajectory (or stop request) received at host time `host_us`; its signature is the
  // driver's to check before.
  void OnTrajectory(const selfcal::joint_trajectory_t& message, std::int64_t host_us);
  void OnStreamCommand(const drake::lcmt_iiwa_command& message, std::int64_t host_us);
  // Publishes a refusal of `id` (the same reason at most once a second).
  void Refuse(const std::string& id, const std::string& reason, std::int64_t host_us);
  // Call regularly: detects a silent controller.
  void CheckSilence(std::int64_t host_us);

  std::vector<SessionEvent> TakeEvents();

  // -1 before the first message or after silence.
  int session_state() const { return session_state_; }
  int quality() const { return quality_; }
  std::int8_t command_source() const { return source_; }
  const std::string& trajectory_id() const { return trajectory_id_; }
  double trajectory_time() const { return trajectory_time_; }
  // Controller time [us] at which the current trajectory started (t = 0); -1 if none.
  std::int64_t trajectory_start_device_us() const { return trajectory_start_device_us_; }
  std::int64_t messages_received() const { return received_; }
  std::int64_t messages_lost() const { return lost_; }
  std::int64_t messages_late() const { return late_; }
  std::int64_t replies_sent() const { return replies_; }
  std::int64_t limited_cycles() const { return limited_cycles_; }
  const Eigen::VectorXd& commanded() const { return commanded_; }
  const Eigen::VectorXd& measured() const { return measured_; }

 private:
  // A change of the FRI session state: aborts the motion when commanding ends.
  void OnSessionState(int state);
  // The reply's command for this cycle: the IPO position in COMMANDING_WAIT, the active source's
  // in COMMANDING_ACTIVE, none otherwise.
  std::optional<fri::CommandData> CommandFor(const fri::MonitoringMessage& m, int state,
                                             std::int64_t device_us, std::int64_t host_us,
                                             double dt);
  Eigen::VectorXd Command(std::int64_t device_us, std::int64_t host_us, double dt);
  Eigen::VectorXd Brake(double dt);
  void StartStopping(const std::string& reason);
  void Emit(std::int8_t event, const std::string& message);
  void Refuse(const std::string& id, const std::string& reason);
  std::string FarFromCurrent(const Eigen::VectorXd& start) const;

  SessionOptions options_;
  Eigen::Index n_;
  int session_state_ = -1;
  int quality_ = -1;
  std::int8_t source_ = selfcal::robot_driver_status_t::SOURCE_NONE;
  // The controller's 32-bit sequence counter: gaps are lost datagrams, a step back a late one.
  timing::CounterUnwrapper sequence_{
      timing::CounterOptions::Bits(32, timing::CounterOptions::Backwards::kIgnore)};
  std::uint32_t own_sequence_ = 0;
  std::uint32_t multiplier_counter_ = 0;
  std::int64_t last_rx_host_us_ = -1;
  std::int64_t last_device_us_ = -1;
  std::int64_t received_ = 0, lost_ = 0, late_ = 0, replies_ = 0, limited_cycles_ = 0;

  Eigen::VectorXd measured_, commanded_, commanded_velocity_, hold_;
  bool have_commanded_ = false;

  // Trajectory execution.
  std::optional<trajectory::JointTrajectory> trajectory_;
  std::string trajectory_id_;
  std::int64_t trajectory_start_device_us_ = -1;
  Eigen::VectorXd start_offset_;
  double trajectory_time_ = 0;

  // Drake command stream: the last setpoints with their host receive times. The driver follows
  // them one stream period late, interpolating linearly, so a 100 Hz stream becomes smooth
  // motion at the FRI rate instead of steps.
  struct StreamPoint {
    std::int64_t host_us = 0;
    Eigen::VectorXd position;
  };
  std::vector<StreamPoint> stream_;  // oldest first, at most kStreamPoints
  static constexpr std::size_t kStreamPoints = 4;
  std::int64_t stream_host_us_ = -1;
  // The interpolated stream target at host time `host_us` and its velocity.
  void StreamTarget(std::int64_t host_us, Eigen::VectorXd& target, Eigen::VectorXd& velocity) const;

  std::vector<SessionEvent> events_;
  std::string last_refusal_;
  std::int64_t last_refusal_host_us_ = 0;
  std::int64_t now_host_us_ = 0;
};

}  // namespace selfcal::iiwa
