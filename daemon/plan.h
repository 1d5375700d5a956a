// Scan plans the daemon executes: for each scan, move to `from`, wait, sweep to `to` while the
// sensor records (between BEGIN and END markers), wait. Depth-camera scans use from == to.
// The file format (config/daemon/plans/*.yaml):
//   name: demo
//   mode: remaster   # optional: full (the default, the model file's mask) or remaster
//   scans:
//     - {purpose: fit, from: [q1..qn], to: [q1..qn], speed: 0.4}   # rad/s (m/s) peak joint speed
#pragma once

#include <string>
#include <vector>

#include "core/model/robot_model.h"
#include "core/sim/scan_plan.h"
#include "core/trajectory/joint_trajectory.h"
#include "core/util/expected.h"

namespace selfcal::daemon {

struct PlannedScan {
  bool validation = false;  // held back for validation (scan_marker_t.VALIDATION)
  std::vector<double> from;
  std::vector<double> to;
  double speed = 0;  // rad/s (m/s) peak joint speed during the sweep
};

// What a session of the plan calibrates: everything the model file's mask selects, or (a quick
// remastering after a motor or gearbox swap) only the joints' zero offsets and the sensor mount
// (daemon/remaster.h; docs/daemon.md "Quick remastering").
enum class PlanMode { kFull, kRemaster };
const char* PlanModeName(PlanMode mode);

struct ScanPlan {
  std::string name;
  PlanMode mode = PlanMode::kFull;
  std::vector<PlannedScan> scans;
};

Expected<ScanPlan> ReadScanPlan(const std::string& path);
Expected<ScanPlan> ParseScanPlan(const std::string& text, const std::string& path);
// The file's text (the format above; joints with 17 digits, so that reading it back gives the
// same plan), after `comment` as a comment line. The one writer of plan files.
std::string FormatScanPlan(const ScanPlan& plan, const std::string& comment);
// A simulation's or the planner's plan (core/sim/scan_plan.h) as the daemon's: a sweep's speed
// is its peak joint speed (the plan's rate along the line times the largest joint travel), a
// stationary scan's 0.1.
ScanPlan FromSimulatedPlan(const std::string& name, const sim::ScanPlan& plan);
// The other way, for `selfcal simulate --plan`: a sweep's rate along its line is its speed over
// the largest joint travel; a scan whose only moving joint is one axis names it (LiDAR).
sim::ScanPlan ToSimulatedPlan(const ScanPlan& plan);

// Every waypoint has one value per joint and lies `margin` inside the joint limits; sweep speeds
// are within the velocity limits; at least one fit and one validation scan. Empty when fine.
std::string CheckPlan(const ScanPlan& plan, const RobotModel& model, double margin);

// The motion of a plan as one trajectory for the arm's driver (selfcal.joint_trajectory_t): for
// each scan, a synchronized point-to-point move to `from` within `speed_fraction` of each
// joint's velocity and acceleration limits, `settle_time` standing still, the sweep to `to`,
// `settle_time` standing still. Times are seconds from the start of the trajectory.
struct ScanTiming {
  int scan_index = 0;
  bool validation = false;
  double move_begin = 0;  // leaves for the scan's `from`
  double begin = 0;       // the sweep starts: BEGIN marker
  double end = 0;         // the sweep is over: END marker
};
struct ScanMotion {
  trajectory::JointTrajectory trajectory;
  std::vector<ScanTiming> scans;  // in the plan's order
};
Expected<ScanMotion> PlanScanMotion(const ScanPlan& plan, const std::vector<double>& start,
                                    const RobotModel& model, double speed_fraction,
                                    double settle_time);

// A scan's sweep, rest to rest, with peak joint speed `speed`: the plan sets the point density
// (a LiDAR's line spacing) through it and CheckPlan keeps it within the velocity limits, so the
// moves' speed_fraction does not slow it (that doubled the demo's points and computation). A
// depth-camera scan (from == to) stands still for `settle_time`, so that it records a moment.
Expected<trajectory::JointTrajectory> PlanSweep(const PlannedScan& scan, const RobotModel& model,
                                                double settle_time);

}  // namespace selfcal::daemon
