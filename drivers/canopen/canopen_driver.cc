#include "drivers/canopen/canopen_driver.h"

#include <poll.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>

#include "core/timing/host_clock.h"
#include "selfcal/robot_driver_status_t.hpp"

namespace selfcal::canopen {
namespace {}  // namespace

CanopenDriver::CanopenDriver(CanopenDriverOptions options, std::unique_ptr<CanSocket> socket,
                             Bus& bus)
    : options_(std::move(options)),
      socket_(std::move(socket)),
      bus_(bus),
      source_(options_.config, options_.clock) {
  const auto n = options_.config.joints.size();
  joint_state_.num_joints = static_cast<std::int32_t>(n);
  for (const JointConfig& joint : options_.config.joints) joint_state_.names.push_back(joint.name);
  joint_state_.positions.resize(n);
  joint_state_.velocities.resize(n);
  joint_state_.efforts.assign(n, std::nan(""));
}

void CanopenDriver::PublishStatus(std::int8_t event, const std::string& message,
                                  std::int64_t host_us) {
  selfcal::robot_driver_status_t status;
  status.utime = host_us;
  status.session_state = -1;
  status.connection_quality = -1;
  status.command_source = selfcal::robot_driver_status_t::SOURCE_NONE;
  status.event = event;
  status.trajectory_time = 0;
  status.messages_received = source_.syncs() + 1;
  status.messages_lost = source_.incomplete_syncs();
  status.messages_late = 0;
  status.decode_errors = source_.bad_frames();
  status.replies_sent = 0;
  status.clock_settled = source_.clock().settled();
  status.clock_drift_ppm = source_.clock().drift_ppm();
  status.message = message.empty() ? "ok" : message;
  (void)bus_.Publish(options_.status_channel, status);
  last_status_us_ = host_us;
}

Status CanopenDriver::SpinOnce(std::chrono::microseconds timeout) {
  pollfd fd{socket_->fd(), POLLIN, 0};
  timespec ts{static_cast<time_t>(timeout.count() / 1000000),
              static_cast<long>((timeout.count() % 1000000) * 1000)};
  const int ready = ::ppoll(&fd, 1, &ts, nullptr);
  if (ready < 0 && errno != EINTR) return Error{std::string("poll: ") + std::strerror(errno)};
  if (ready > 0) {
    while (true) {
      auto frame = socket_->Read();
      if (!frame.ok()) return frame.error();
      if (!*frame) break;
      source_.OnFrame(**frame, timing::RealtimeUs());
    }
  }
  const std::int64_t now = timing::RealtimeUs();
  for (const CanFrame& frame : source_.Tick(now)) {
    if (auto s = socket_->Write(frame); !s.ok()) return s;
  }
  for (const JointSample& sample : source_.TakeSamples()) {
    joint_state_.utime = sample.host_us;
    joint_state_.device_utime = sample.device_us;
    joint_state_.positions = sample.positions;
    joint_state_.velocities = sample.velocities;
    (void)bus_.Publish(options_.joint_state_channel, joint_state_);
    ++published_;
  }
  for (const SourceEvent& event : source_.TakeEvents()) {
    PublishStatus(selfcal::robot_driver_status_t::EVENT_SESSION, event.message, now);
  }
  if (now - last_status_us_ >= static_cast<std::int64_t>(options_.status_period_s * 1e6)) {
    PublishStatus(selfcal::robot_driver_status_t::EVENT_PERIODIC, "", now);
  }
  return OkStatus();
}

}  // namespace selfcal::canopen
