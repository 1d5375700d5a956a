#include "tests/daemon/test_arm.h"

#include <cmath>

#include "drake/lcmt_iiwa_command.hpp"
#include "selfcal/joint_state_t.hpp"
#include "selfcal/range_scan_t.hpp"

namespace selfcal::daemon::testing {

TestArm::TestArm(std::shared_ptr<Bus> bus, TestArmOptions options)
    : position(options.joint_names.size(), 0.0),
      bus_(std::move(bus)),
      options_(std::move(options)),
      target_(position) {
  bus_->Subscribe(options_.command_channel, [this](const BusMessage& message) {
    auto command = DecodeLcm<drake::lcmt_iiwa_command>(message.data, message.channel);
    if (command && command->joint_position.size() == target_.size()) {
      target_ = command->joint_position;
      ++commands;
    }
  });
}

void TestArm::Tick(std::int64_t now) {
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
