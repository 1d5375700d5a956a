// Scan plans the daemon executes: for each scan, move to `from`, wait, sweep to `to` while the
// sensor records (between BEGIN and END markers), wait. Depth-camera scans use from == to.
// The file format (config/plans/*.yaml):
//   name: demo
//   scans:
//     - {purpose: fit, from: [q1..qn], to: [q1..qn], speed: 0.4}   # rad/s (m/s) peak joint speed
#pragma once

#include <string>
#include <vector>

#include "core/model/robot_model.h"
#include "core/util/expected.h"

namespace selfcal::daemon {

struct PlannedScan {
  bool validation = false;  // held back for validation (scan_marker_t.VALIDATION)
  std::vector<double> from;
  std::vector<double> to;
  double speed = 0;  // rad/s (m/s) peak joint speed during the sweep
};

struct ScanPlan {
  std::string name;
  std::vector<PlannedScan> scans;
};

Expected<ScanPlan> ReadScanPlan(const std::string& path);
Expected<ScanPlan> ParseScanPlan(const std::string& text, const std::string& path);

// Every waypoint has one value per joint and lies `margin` inside the joint limits; sweep speeds
// are within the velocity limits; at least one fit and one validation scan. Empty when fine.
std::string CheckPlan(const ScanPlan& plan, const RobotModel& model, double margin);

// A synchronized point-to-point motion: all joints start and stop together on a trapezoidal
// profile (a quarter of the time accelerating, a quarter braking) within each joint's
// velocity and acceleration limits scaled by `fraction`, and `speed_cap` when positive.
struct Motion {
  std::vector<double> from;
  std::vector<double> to;
  double duration = 0;                     // s
  std::vector<double> At(double t) const;  // position at time t since the start
};
Motion PlanMotion(const std::vector<double>& from, const std::vector<double>& to,
                  const RobotModel& model, double fraction, double speed_cap);
// A scan's sweep at the plan's peak speed: the plan sets the point density (a LiDAR's line
// spacing) through `speed`, and CheckPlan keeps it within the velocity limits, so the moves'
// motion.speed_fraction does not slow it (that doubled the demo's points and computation).
Motion PlanSweep(const PlannedScan& scan, const RobotModel& model);

}  // namespace selfcal::daemon
