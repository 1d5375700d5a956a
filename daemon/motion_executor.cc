#include "daemon/motion_executor.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "daemon/clock.h"
#include "protocols/trajectory/trajectory_message.h"
#include "protocols/trajectory/trajectory_signature.h"
#include "selfcal/joint_trajectory_t.hpp"

namespace selfcal::daemon {
namespace {

using DriverStatus_t = selfcal::robot_driver_status_t;

}  // namespace

MotionExecutor::MotionExecutor(std::shared_ptr<Bus> bus, std::string trajectory_channel,
                               CheckConfig checks, auth::Key key)
    : bus_(std::move(bus)), channel_(std::move(trajectory_channel)), checks_(checks), key_(key) {}

Status MotionExecutor::Start(ScanMotion motion, const std::vector<std::string>& joint_names,
                             const std::string& trajectory_id, std::int64_t now,
                             std::int64_t stamp) {
  motion_ = std::move(motion);
  joint_names_ = joint_names;
  id_ = trajectory_id;
  start_utime_ = now;
  driver_failure_.clear();
  boundaries_.clear();
  for (const auto& scan : motion_.scans) {
    // The first move starts with the motion itself.
    if (scan.scan_index > 0)
      boundaries_.push_back({scan.move_begin, MotionEvent::Kind::kMoveToScan, scan});
    boundaries_.push_back({scan.begin, MotionEvent::Kind::kScanBegin, scan});
    boundaries_.push_back({scan.end, MotionEvent::Kind::kScanEnd, scan});
  }
  boundaries_.push_back({motion_.trajectory.duration(), MotionEvent::Kind::kCompleted, {}});
  std::stable_sort(boundaries_.begin(), boundaries_.end(),
                   [](const Boundary& a, const Boundary& b) { return a.time < b.time; });
  next_boundary_ = 0;
  auto message = ToMessage(motion_.trajectory, joint_names_, id_, stamp);
  SignTrajectory(message, key_);
  if (auto published = bus_->Publish(channel_, message); !published) return published.error();
  active_ = true;
  return OkStatus();
}

std::int64_t MotionExecutor::next_deadline() const {
  if (!active_ || next_boundary_ >= boundaries_.size()) return 0;
  return start_utime_ + Us(boundaries_[next_boundary_].time);
}

void MotionExecutor::OnDriverStatus(const DriverStatus_t& status) {
  if (!active_ || status.trajectory_id != id_ || !driver_failure_.empty()) return;
  if (status.event == DriverStatus_t::EVENT_REFUSED) {
    driver_failure_ = "the arm's driver refused the trajectory: " + status.message;
  } else if (status.event == DriverStatus_t::EVENT_STOPPED) {
    driver_failure_ = "the arm's driver stopped the trajectory: " + status.message;
  }
}

std::string MotionExecutor::CheckInputs(std::int64_t now, const MotionInputs& inputs) {
  if (!driver_failure_.empty()) return driver_failure_;
  const std::int64_t joint_age = now - inputs.joint_utime;
  if (joint_age > Us(checks_.joint_state_max_age)) {
    return "joint states went stale during motion (last one " + Millis(joint_age) + " ago)";
  }
  const std::int64_t sensor_age = now - inputs.sensor_utime;
  if (sensor_age > Us(checks_.sensor_max_age)) {
    return "sensor dropout during motion (last message " + Millis(sensor_age) + " ago)";
  }
  return CheckDeviation(inputs);
}

// The measured position against the trajectory near the time of the measurement. The arm follows
// its setpoints with a lag (transport, controller cycle, servo), so the smallest deviation from
// the trajectory over the last `checks.max_lag_s` is what counts.
std::string MotionExecutor::CheckDeviation(const MotionInputs& inputs) const {
  if (inputs.joint_utime < start_utime_ || !inputs.joint_positions) return {};
  const auto& measured = *inputs.joint_positions;
  const double t = static_cast<double>(inputs.joint_utime - start_utime_) * 1e-6;
  double best = std::numeric_limits<double>::infinity();
  std::size_t worst_joint = 0;
  for (double lag = 0; lag <= checks_.max_lag + 1e-9; lag += 0.005) {
    const Eigen::VectorXd expected = motion_.trajectory.Evaluate(t - lag).position;
    double worst = 0;
    std::size_t joint = 0;
    for (std::size_t j = 0; j < measured.size() && j < static_cast<std::size_t>(expected.size());
         ++j) {
      const double deviation = std::abs(measured[j] - expected[static_cast<Eigen::Index>(j)]);
      if (deviation > worst) {
        worst = deviation;
        joint = j;
      }
    }
    if (worst < best) {
      best = worst;
      worst_joint = joint;
    }
  }
  if (best <= checks_.max_deviation) return {};
  std::ostringstream why;
  why << "joint " << joint_names_.at(worst_joint) << " deviates from the trajectory by " << best
      << " (limit " << checks_.max_deviation << " within " << checks_.max_lag << " s of lag)";
  return why.str();
}

std::vector<MotionEvent> MotionExecutor::Tick(std::int64_t now, std::int64_t stamp,
                                              const MotionInputs& inputs) {
  std::vector<MotionEvent> events;
  if (!active_) return events;
  if (const std::string failure = CheckInputs(now, inputs); !failure.empty()) {
    Stop(stamp);
    events.push_back({MotionEvent::Kind::kFailed, {}, failure});
    return events;
  }
  const double t = static_cast<double>(now - start_utime_) * 1e-6;
  while (next_boundary_ < boundaries_.size() && boundaries_[next_boundary_].time <= t) {
    const Boundary& boundary = boundaries_[next_boundary_++];
    events.push_back({boundary.kind, boundary.scan, {}});
    if (boundary.kind == MotionEvent::Kind::kCompleted) active_ = false;
  }
  return events;
}

void MotionExecutor::Stop(std::int64_t stamp) {
  if (!active_) return;
  active_ = false;
  StopDriver(id_, stamp);
}

void MotionExecutor::StopDriver(const std::string& trajectory_id, std::int64_t stamp) {
  selfcal::joint_trajectory_t stop;
  stop.utime = stamp;
  stop.trajectory_id = trajectory_id;
  stop.num_joints = 0;
  stop.num_points = 0;
  stop.valid_until = 0;
  stop.tag_length = 0;
  SignTrajectory(stop, key_);
  if (auto published = bus_->Publish(channel_, stop); !published) {
    spdlog::warn("{}", published.error().message);
  }
}

}  // namespace selfcal::daemon
