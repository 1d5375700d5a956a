// Scan plans as the paper recorded them (section "Evaluation"):
// - rotating LiDAR: random configurations, each moving one axis by 180 degrees at a speed that
//   gives a similar density within and between scan lines;
// - line scanner: constant-velocity joint-space sweeps between a start and an end configuration
//   found by inverse kinematics for chosen sensor poses;
// - depth cameras: fixed configurations from which the sensor sees the object within its range.
// Plans are computed with the nominal model (as the paper's authors did) and always within the
// joint limits. Scan k of a purpose depends only on (seed, purpose, k), so the first 7 scans of
// a 28-scan plan are the 7-scan plan, and the validation scans are the same for every size.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "core/model/robot_model.h"
#include "core/sim/scene.h"
#include "core/sim/sensor_model.h"
#include "core/util/expected.h"

namespace selfcal::sim {

enum class ScanPurpose { kFit, kValidation };

struct PlannedScan {
  ScanPurpose purpose = ScanPurpose::kFit;
  std::vector<double> start;  // joint positions
  std::vector<double> end;    // == start for a stationary scan
  double peak_rate = 0;       // 1/s along the start->end line; 0 for a stationary scan
  int moving_joint = -1;      // LiDAR: the axis that turns
};

struct ScanPlan {
  std::vector<PlannedScan> scans;  // fit scans first, then validation scans
};

// Where the sensor looks from: spherical coordinates around a target point. Azimuth 0 points
// from the target towards the robot's base (so the sensor stands between robot and target).
struct ViewOptions {
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  double target_jitter = 0.0;                       // m, uniform per axis
  double distance_min = 0.5, distance_max = 0.8;    // m, sensor origin to target
  double elevation_min = 0.5, elevation_max = 1.2;  // rad above the horizontal
  double azimuth_min = -1.0, azimuth_max = 1.0;     // rad
  double roll_min = -0.5, roll_max = 0.5;           // rad about the optical axis
};

struct PlanOptions {
  enum class Kind { kStationaryViews, kLineSweeps, kLidarSweeps };
  Kind kind = Kind::kStationaryViews;
  int fit_scans = 7;
  int validation_scans = 7;
  std::uint64_t seed = 1;
  double free_margin = 0.08;   // m: the sensor keeps this far from obstacles and walls
  double limit_margin = 0.05;  // rad: kept from every joint limit
  // m: > 0, the arm's links too, as capsules of this radius (LinksAreFree), keep clear of the
  // scene at every scan and along every sweep, and the scans are ordered so that the moves
  // between them do (OrderForFreeMoves). 0: the sensor's origin only, in the order generated.
  double link_radius = 0;
  ViewOptions view;           // stationary views and line sweeps
  double sweep_length = 0.2;  // m: line sweeps, along the sensor's y axis
  double sweep_speed = 0.05;  // m/s: line sweeps, sensor speed in the middle of the sweep
  double sweep_angle = 3.141592653589793;  // rad: LiDAR sweeps
  double joint_speed = 0.35;               // rad/s: LiDAR sweeps
  int max_attempts = 400;                  // candidate poses per scan before giving up
};

// `nominal` includes the sensor mount in its tool. The error names the scan that failed.
Expected<ScanPlan> MakeScanPlan(const RobotModel& nominal, const SensorModel& sensor,
                                const Scene& scene, const PlanOptions& options);

// True when the arm's links at `q` keep `radius` inside the workspace and outside every obstacle
// of `scene`: the links as the field effects see them (ArmCapsules of field_effects.h, between
// consecutive joint origins and on to the sensor's origin; the one from the base origin up to the
// first joint, the arm's mount, is left out), their axes checked every 2 cm with Scene::IsFree.
// An approximation: capsules, not the links' meshes; boxes grown by `radius`, not rounded.
bool LinksAreFree(const RobotModel& model, const Scene& scene, const std::vector<double>& q,
                  double radius);

// True when the links (LinksAreFree with `radius`) stay clear all along the straight joint-space
// line from `from` to `to`, the daemon's point-to-point move between scans, checked at most
// 0.02 rad of any joint apart.
bool MoveIsFree(const RobotModel& model, const Scene& scene, const std::vector<double>& from,
                const std::vector<double>& to, double radius);

// The plan's scans in an order the daemon can move through: fit scans first, from the first one
// on, then validation scans, each next scan the nearest remaining one of its group (by the
// largest joint difference) whose move from the scan before is free (MoveIsFree); a scan that
// no free move reaches from the last one goes where it fits between two of its group. The move
// to the first scan is not checked: where the arm starts is not known. An error names the scan
// where neither works.
Expected<ScanPlan> OrderForFreeMoves(const RobotModel& model, const Scene& scene, ScanPlan plan,
                                     double radius);

// The moves between consecutive scans of `plan` that do not keep the links clear (MoveIsFree):
// k for the move from scan k - 1 to scan k.
std::vector<std::size_t> BlockedMoves(const RobotModel& model, const Scene& scene,
                                      const ScanPlan& plan, double radius);

// The joint travel of a plan's moves between scans [rad]: the sum over consecutive scans of the
// largest joint difference, which sets how long a synchronized point-to-point move takes.
double JointTravel(const ScanPlan& plan);

// The LiDAR joint speed of the paper: the sensor turns by `line_spacing` angle increments per
// rotation, so that scan lines are as far apart as the rays within a line (line_spacing = 1).
double LidarJointSpeed(const SensorModel& lidar, double line_spacing);

}  // namespace selfcal::sim
