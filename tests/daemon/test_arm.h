// A stand-in for the arm and the sensor, lighter than the FRI simulator, selfcal-iiwa and the
// Hokuyo chain: executes selfcal.joint_trajectory_t (a setpoint sampled from the trajectory at
// every tick, followed with a first-order lag; an empty trajectory stops it where it is),
// publishes selfcal.joint_state_t and selfcal.range_scan_t (constant ranges; content is not
// checked here) and selfcal.robot_driver_status_t (always COMMANDING_ACTIVE, holding or
// executing). Knobs make it misbehave on purpose: silent joints or sensor, an offset on one
// joint.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/trajectory/joint_trajectory.h"
#include "protocols/bus/bus.h"

namespace selfcal::daemon::testing {

struct TestArmOptions {
  std::vector<std::string> joint_names = {"A1", "A2", "A3", "A4", "A5", "A6", "A7"};
  double joint_rate_hz = 200;
  double sensor_rate_hz = 40;
  double lag = 0.01;  // s, time constant of the servo
  std::string joint_channel = "SELFCAL_JOINT_STATE";
  std::string sensor_channel = "SELFCAL_RANGE_SCAN";
  std::string command_channel = "SELFCAL_JOINT_TRAJECTORY";
  std::string status_channel = "SELFCAL_ROBOT_STATUS";  // as selfcal-iiwa, at 10 Hz
};

class TestArm {
 public:
  TestArm(std::shared_ptr<Bus> bus, TestArmOptions options);
  // Publishes what is due at host time `now_utime`.
  void Tick(std::int64_t now_utime);

  bool joints_silent = false;
  bool sensor_silent = false;
  double offset_joint_0 = 0;  // rad added to the measured A1
  std::size_t commands = 0;   // setpoints taken from trajectories
  std::vector<double> position;

 private:
  std::shared_ptr<Bus> bus_;
  TestArmOptions options_;
  std::vector<double> target_;
  std::optional<trajectory::JointTrajectory> trajectory_;
  std::int64_t trajectory_start_ = -1;  // -1: starts at the next tick
  std::int64_t last_update_ = 0, next_joint_ = 0, next_sensor_ = 0, next_status_ = 0,
               scan_counter_ = 0;
};

}  // namespace selfcal::daemon::testing
