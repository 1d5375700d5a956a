#include "tests/daemon/test_arm.h"

#include <cmath>

#include "protocols/trajectory/trajectory_message.h"
#include "selfcal/joint_state_t.hpp"
#include "selfcal/joint_trajectory_t.hpp"
#include "selfcal/range_scan_t.hpp"
#include "selfcal/robot_driver_status_t.hpp"

namespace selfcal::daemon::testing {

TestArm::TestArm(std::shared_ptr<Bus> bus, TestArmOptions options)
    : position(options.joint_names.size(), 0.0),
      bus_(std::move(bus)),
      options_(std::move(options)),
      target_(position) {
  bus_->Subscribe(options_.command_channel, [this](const BusMessage& message) {
    auto command = DecodeLcm<selfcal::joint_trajectory_t>(message.data, message.channel);
    if (!command) return;
    trajectory_.reset();
    if (command->num_points == 0) {
      target_ = position;  // stop: stand where it is
      return;
    }
    auto trajectory = FromMessage(*command, options_.joint_names);
    if (!trajectory) return;
    trajectory_ = std::move(trajectory).value();
    trajectory_start_ = -1;
  });
}

void TestArm::Tick(std::int64_t now) {
  if (trajectory_) {
    if (trajectory_start_ < 0) trajectory_start_ = now;
    const double t = static_cast<double>(now - trajectory_start_) * 1e-6;
    const Eigen::VectorXd q = trajectory_->Evaluate(t).position;
    target_.assign(q.data(), q.data() + q.size());
    ++commands;
    if (t >= trajectory_->duration()) trajectory_.reset();
  }
  if (last_update_ != 0) {
    const double dt = static_cast<double>(now - last_update_) * 1e-6;
    const double gain = 1.0 - std::exp(-dt / options_.lag);
    for (std::size_t j = 0; j < position.size(); ++j)
      position[j] += gain * (target_[j] - position[j]);
  }
  last_update_ = now;
  if (now >= next_joint_) {
    next_joint_ = now + static_cast<std::int64_t>(1e6 / options_.joint_rate_hz);
    if (!joints_silent) {
      selfcal::joint_state_t state;
      state.utime = now;
      state.device_utime = -1;
      state.num_joints = static_cast<std::int32_t>(position.size());
      state.names = options_.joint_names;
      state.positions = position;
      state.positions[0] += offset_joint_0;
      state.velocities.assign(position.size(), 0.0);
      state.efforts.assign(position.size(), NAN);
      (void)bus_->Publish(options_.joint_channel, state);
    }
  }
  if (now >= next_status_) {
    next_status_ = now + 100'000;
    selfcal::robot_driver_status_t status{};
    status.utime = now;
    status.session_state = 4;  // COMMANDING_ACTIVE
    status.connection_quality = 3;
    status.command_source = trajectory_ ? selfcal::robot_driver_status_t::SOURCE_TRAJECTORY
                                        : selfcal::robot_driver_status_t::SOURCE_HOLD;
    status.event = selfcal::robot_driver_status_t::EVENT_PERIODIC;
    status.message = "ok";
    (void)bus_->Publish(options_.status_channel, status);
  }
  if (now >= next_sensor_) {
    next_sensor_ = now + static_cast<std::int64_t>(1e6 / options_.sensor_rate_hz);
    if (!sensor_silent) {
      selfcal::range_scan_t scan;
      scan.utime = now;
      scan.device_utime = -1;
      scan.scan_counter = scan_counter_++;
      scan.time_per_ray = 1.0 / 40 / 1440;
      scan.angle_first = -2.35619;
      scan.angle_increment = 0.004363;
      scan.num_ranges = 1081;
      scan.ranges.assign(1081, 1.5f);
      scan.num_intensities = 0;
      (void)bus_->Publish(options_.sensor_channel, scan);
    }
  }
}

}  // namespace selfcal::daemon::testing
