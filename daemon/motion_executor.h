// Executes a session's motion: publishes the whole scan motion as one selfcal.joint_trajectory_t
// for the arm's driver (selfcal-iiwa executes it at the FRI rate), says when each scan begins
// and ends, and supervises it. Every tick: stale joint states, a sensor dropout, a measured joint
// further than `checks.max_deviation` from the trajectory at the measurement's time, or the
// driver refusing or stopping the trajectory fail the motion and stop the arm (an empty
// trajectory: the driver brakes within the acceleration limits and holds). Every trajectory it
// publishes, stops included, is signed with the daemon's key (the driver executes nothing else).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/util/expected.h"
#include "daemon/config.h"
#include "daemon/plan.h"
#include "protocols/auth/key.h"
#include "protocols/bus/bus.h"
#include "selfcal/robot_driver_status_t.hpp"

namespace selfcal::daemon {

// What the daemon last heard from the arm and the sensor, on the daemon's monotonic clock [us].
struct MotionInputs {
  std::int64_t joint_utime = 0;  // 0 = never
  const std::vector<double>* joint_positions = nullptr;
  std::int64_t sensor_utime = 0;
};

struct MotionEvent {
  enum class Kind { kMoveToScan, kScanBegin, kScanEnd, kCompleted, kFailed };
  Kind kind = Kind::kMoveToScan;
  ScanTiming scan;     // kMoveToScan, kScanBegin, kScanEnd
  std::string reason;  // kFailed
};

class MotionExecutor {
 public:
  MotionExecutor(std::shared_ptr<Bus> bus, std::string trajectory_channel, CheckConfig checks,
                 auth::Key key);

  // Publishes the trajectory under `trajectory_id`, stamped `stamp` (wall time, the driver's
  // host time); t = 0 is `now` (monotonic, as every time below but the stamps). `joint_names`
  // are the robot model's, base to tip (the driver checks them).
  Status Start(ScanMotion motion, const std::vector<std::string>& joint_names,
               const std::string& trajectory_id, std::int64_t now, std::int64_t stamp);
  // What happened up to `now`, in order. A kFailed or kCompleted event ends the motion; a stop
  // it sends is stamped `stamp`.
  std::vector<MotionEvent> Tick(std::int64_t now, std::int64_t stamp, const MotionInputs& inputs);
  // The driver's account of our trajectory: a refusal or a stop fails the motion at the next tick.
  void OnDriverStatus(const selfcal::robot_driver_status_t& status);
  // Stops the arm where it is (abort); nothing when no motion is active. `stamp`: wall time.
  void Stop(std::int64_t stamp);
  // Stops whatever the arm's driver executes, ours or not: a trajectory a killed daemon left
  // running.
  void StopDriver(const std::string& trajectory_id, std::int64_t stamp);

  bool active() const { return active_; }
  // When the next scan boundary is due [us, monotonic]; the caller wakes up for it. 0 when
  // inactive.
  std::int64_t next_deadline() const;

 private:
  struct Boundary {
    double time;  // s from the start
    MotionEvent::Kind kind;
    ScanTiming scan;
  };
  std::string CheckInputs(std::int64_t now, const MotionInputs& inputs);
  std::string CheckDeviation(const MotionInputs& inputs) const;

  std::shared_ptr<Bus> bus_;
  std::string channel_;
  CheckConfig checks_;
  auth::Key key_;
  std::vector<std::string> joint_names_;

  bool active_ = false;
  ScanMotion motion_;
  std::string id_;
  std::int64_t start_utime_ = 0;
  std::vector<Boundary> boundaries_;  // in time order
  std::size_t next_boundary_ = 0;
  std::string driver_failure_;
};

}  // namespace selfcal::daemon
