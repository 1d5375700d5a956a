// selfcal-canopen: joint states of a CANopen (CiA 402) arm over SocketCAN, published as
// selfcal.joint_state_t (SYNC-based timestamps) with driver status on SELFCAL_ROBOT_STATUS
// (selfcal.robot_driver_status_t: session_state and quality -1 (not FRI), messages_received =
// SYNCs, messages_lost = SYNC cycles with a missing TPDO, decode_errors = bad frames, the message
// names node events: boot-up, state changes, heartbeat lost, emergencies).
#pragma once

#include <chrono>
#include <memory>

#include "drivers/canopen/can_socket.h"
#include "drivers/canopen/canopen_source.h"
#include "protocols/bus/bus.h"
#include "protocols/lcm/channels.h"
#include "selfcal/joint_state_t.hpp"

namespace selfcal::canopen {

struct CanopenDriverOptions {
  CanopenConfig config;
  std::string joint_state_channel = channels::kJointState;
  std::string status_channel = channels::kRobotStatus;
  double status_period_s = 0.1;
  timing::ClockFilterOptions clock;
};

class CanopenDriver {
 public:
  CanopenDriver(CanopenDriverOptions options, std::unique_ptr<CanSocket> socket, Bus& bus);
  // Waits up to `timeout` for frames, handles them, sends what is due (NMT, SYNC), publishes.
  Status SpinOnce(std::chrono::microseconds timeout);
  const CanopenSource& source() const { return source_; }
  std::int64_t published() const { return published_; }

 private:
  void PublishStatus(std::int8_t event, const std::string& message, std::int64_t host_us);

  CanopenDriverOptions options_;
  std::unique_ptr<CanSocket> socket_;
  Bus& bus_;
  CanopenSource source_;
  selfcal::joint_state_t joint_state_;
  std::int64_t published_ = 0;
  std::int64_t last_status_us_ = 0;
};

}  // namespace selfcal::canopen
