#include "core/sim/scan_plan.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>

#include "core/model/kinematics.h"
#include "core/sim/field_effects.h"
#include "core/sim/ik.h"
#include "core/sim/random.h"

namespace selfcal::sim {
namespace {

constexpr std::uint64_t kFitLabel = 0xf17;
constexpr std::uint64_t kValidationLabel = 0x7a11d;

bool WithinLimits(const RobotModel& model, const std::vector<double>& q, double margin) {
  for (std::size_t j = 0; j < q.size(); ++j) {
    if (q[j] < model.joints[j].lower + margin - 1e-12 ||
        q[j] > model.joints[j].upper - margin + 1e-12) {
      return false;
    }
  }
  return true;
}

double LargestJointDifference(const std::vector<double>& from, const std::vector<double>& to) {
  double largest = 0;
  for (std::size_t j = 0; j < from.size(); ++j)
    largest = std::max(largest, std::abs(to[j] - from[j]));
  return largest;
}

// True when `free(q)` holds all along the straight joint-space line from `from` to `to`, checked
// at most 0.02 rad of any joint apart.
template <typename Free>
bool FreeAlongJointLine(const std::vector<double>& from, const std::vector<double>& to,
                        const Free& free) {
  const int steps =
      std::max(1, static_cast<int>(std::ceil(LargestJointDifference(from, to) / 0.02)));
  std::vector<double> q(from.size());
  for (int s = 0; s <= steps; ++s) {
    for (std::size_t j = 0; j < q.size(); ++j) q[j] = from[j] + (to[j] - from[j]) * s / steps;
    if (!free(q)) return false;
  }
  return true;
}

// The sensor origin stays in free space along the straight joint-space line.
bool PathIsFree(const RobotModel& model, const Scene& scene, const std::vector<double>& from,
                const std::vector<double>& to, double margin) {
  return FreeAlongJointLine(from, to, [&](const std::vector<double>& q) {
    return scene.IsFree(ForwardKinematics(model, q).translation(), margin);
  });
}

// A sensor pose looking at a jittered target from the view sphere.
Eigen::Isometry3d SampleView(const ViewOptions& view, Random& random) {
  const Eigen::Vector3d target =
      view.target +
      Eigen::Vector3d(random.Uniform(-1, 1), random.Uniform(-1, 1), random.Uniform(-1, 1)) *
          view.target_jitter;
  const double distance = random.Uniform(view.distance_min, view.distance_max);
  const double elevation = random.Uniform(view.elevation_min, view.elevation_max);
  const double azimuth = random.Uniform(view.azimuth_min, view.azimuth_max);
  const double roll = random.Uniform(view.roll_min, view.roll_max);
  // Azimuth 0 points from the target towards the base origin, in the horizontal plane.
  Eigen::Vector2d towards_base = -view.target.head<2>();
  if (towards_base.norm() < 1e-6) towards_base = Eigen::Vector2d(-1, 0);
  const double heading = std::atan2(towards_base.y(), towards_base.x()) + azimuth;
  const Eigen::Vector3d offset(std::cos(elevation) * std::cos(heading),
                               std::cos(elevation) * std::sin(heading), std::sin(elevation));
  const Eigen::Vector3d position = target + distance * offset;
  const Eigen::Vector3d z = (target - position).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();  // image right
  const Eigen::Vector3d y = z.cross(x);                                      // image down
  Eigen::Matrix3d R;
  R << x, y, z;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R * Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = position;
  return T;
}

std::optional<PlannedScan> TryStationary(const RobotModel& nominal, const Scene& scene,
                                         const PlanOptions& options, Random& random) {
  const Eigen::Isometry3d goal = SampleView(options.view, random);
  if (!scene.IsFree(goal.translation(), options.free_margin)) return std::nullopt;
  IkOptions ik;
  ik.limit_margin = options.limit_margin;
  ik.restarts = 8;
  const auto q = SolveIk(nominal, goal, {}, random, ik);
  if (!q) return std::nullopt;
  PlannedScan scan;
  scan.start = *q;
  scan.end = *q;
  return scan;
}

std::optional<PlannedScan> TryLineSweep(const RobotModel& nominal, const Scene& scene,
                                        const PlanOptions& options, Random& random) {
  const Eigen::Isometry3d center = SampleView(options.view, random);
  const Eigen::Vector3d along = center.linear().col(1) * (options.sweep_length / 2);
  Eigen::Isometry3d start = center, end = center;
  start.translation() -= along;
  end.translation() += along;
  if (!scene.IsFree(start.translation(), options.free_margin) ||
      !scene.IsFree(end.translation(), options.free_margin)) {
    return std::nullopt;
  }
  IkOptions ik;
  ik.limit_margin = options.limit_margin;
  ik.restarts = 8;
  const auto q_start = SolveIk(nominal, start, {}, random, ik);
  if (!q_start) return std::nullopt;
  ik.restarts = 1;  // the end must be near the start in joint space: seed it there only
  const auto q_end = SolveIk(nominal, end, *q_start, random, ik);
  if (!q_end) return std::nullopt;
  // The joint-space line must stay close to the Cartesian line (no wild wrist flips).
  std::vector<double> middle(q_start->size());
  for (std::size_t j = 0; j < middle.size(); ++j) middle[j] = 0.5 * ((*q_start)[j] + (*q_end)[j]);
  if ((ForwardKinematics(nominal, middle).translation() - center.translation()).norm() > 0.02) {
    return std::nullopt;
  }
  if (!PathIsFree(nominal, scene, *q_start, *q_end, options.free_margin)) return std::nullopt;
  PlannedScan scan;
  scan.start = *q_start;
  scan.end = *q_end;
  scan.peak_rate = options.sweep_speed / options.sweep_length;
  return scan;
}

std::optional<PlannedScan> TryLidarSweep(const RobotModel& nominal, const Scene& scene,
                                         const PlanOptions& options, Random& random) {
  const std::size_t n = nominal.JointCount();
  std::vector<double> q = RandomConfiguration(nominal, options.limit_margin, random);
  const int joint = random.Index(static_cast<int>(n));
  const auto& spec = nominal.joints[static_cast<std::size_t>(joint)];
  const double low = spec.lower + options.limit_margin;
  const double high = spec.upper - options.limit_margin - options.sweep_angle;
  if (high < low) return std::nullopt;
  const double first = random.Uniform(low, high);
  const bool upwards = random.Uniform() < 0.5;
  std::vector<double> start = q, end = q;
  start[static_cast<std::size_t>(joint)] = upwards ? first : first + options.sweep_angle;
  end[static_cast<std::size_t>(joint)] = upwards ? first + options.sweep_angle : first;
  if (!WithinLimits(nominal, start, options.limit_margin) ||
      !WithinLimits(nominal, end, options.limit_margin)) {
    return std::nullopt;
  }
  // A turn about the scan plane's normal only repeats the same line: require the moving axis
  // to lie mostly within the scan plane (|cos| between axis and plane normal below 0.7).
  const Eigen::Isometry3d T0 = ForwardKinematics(nominal, start);
  std::vector<double> nudged = start;
  nudged[static_cast<std::size_t>(joint)] += 1e-6;
  const Eigen::Vector3d axis =
      RotationError(ForwardKinematics(nominal, nudged).linear(), T0.linear());
  if (axis.norm() < 1e-9) return std::nullopt;
  if (std::abs(axis.normalized().dot(T0.linear().col(2))) > 0.7) return std::nullopt;
  if (!PathIsFree(nominal, scene, start, end, options.free_margin)) return std::nullopt;
  PlannedScan scan;
  scan.start = start;
  scan.end = end;
  scan.moving_joint = joint;
  scan.peak_rate = options.joint_speed / options.sweep_angle;
  return scan;
}

}  // namespace

bool LinksAreFree(const RobotModel& model, const Scene& scene, const std::vector<double>& q,
                  double radius) {
  const std::vector<double> parameters = ToParameterVector(model);
  const std::vector<JointType> types = JointTypes(model);
  const std::vector<Capsule> links =
      ArmCapsules(ComputeArmFrames(types, parameters.data(), q.data()), radius);
  for (std::size_t l = 1; l < links.size(); ++l) {  // links[0]: the mount, base to joint 1
    const Eigen::Vector3d axis = links[l].b - links[l].a;
    const int steps = std::max(1, static_cast<int>(std::ceil(axis.norm() / 0.02)));
    for (int s = 0; s <= steps; ++s) {
      if (!scene.IsFree(links[l].a + axis * (static_cast<double>(s) / steps), radius)) return false;
    }
  }
  return true;
}

bool MoveIsFree(const RobotModel& model, const Scene& scene, const std::vector<double>& from,
                const std::vector<double>& to, double radius) {
  return FreeAlongJointLine(from, to, [&](const std::vector<double>& q) {
    return LinksAreFree(model, scene, q, radius);
  });
}

namespace {

// Where `scan` can go between two scans of out[first..] (or after the last) with both moves
// free, the one that adds the least joint travel; nullopt when nowhere.
std::optional<std::size_t> CheapestFreeInsertion(const RobotModel& model, const Scene& scene,
                                                 const PlannedScan& scan,
                                                 const std::vector<PlannedScan>& out,
                                                 std::size_t first, double radius) {
  std::optional<std::size_t> best;
  double best_added = 0;
  for (std::size_t p = std::max<std::size_t>(first, 1); p <= out.size(); ++p) {
    const bool last = p == out.size();
    double added = LargestJointDifference(out[p - 1].end, scan.start);
    if (!last) {
      added += LargestJointDifference(scan.end, out[p].start) -
               LargestJointDifference(out[p - 1].end, out[p].start);
    }
    if (best && added >= best_added) continue;
    if (!MoveIsFree(model, scene, out[p - 1].end, scan.start, radius)) continue;
    if (!last && !MoveIsFree(model, scene, scan.end, out[p].start, radius)) continue;
    best = p;
    best_added = added;
  }
  return best;
}

// Appends `group` to `out`: from its first scan on (or from out's last), the nearest remaining
// scan whose move is free; a scan no free move reaches from the end is put where it fits
// between two of the group's scans (CheapestFreeInsertion).
Status AppendNearestFirst(const RobotModel& model, const Scene& scene,
                          std::vector<PlannedScan> group, double radius,
                          std::vector<PlannedScan>& out) {
  if (group.empty()) return OkStatus();
  const std::size_t first = out.size();
  if (out.empty()) {
    out.push_back(std::move(group.front()));
    group.erase(group.begin());
  }
  while (!group.empty()) {
    const std::vector<double>& at = out.back().end;
    std::vector<std::size_t> nearest(group.size());
    std::iota(nearest.begin(), nearest.end(), 0);
    std::stable_sort(nearest.begin(), nearest.end(), [&](std::size_t a, std::size_t b) {
      return LargestJointDifference(at, group[a].start) <
             LargestJointDifference(at, group[b].start);
    });
    const auto free = std::find_if(nearest.begin(), nearest.end(), [&](std::size_t k) {
      return MoveIsFree(model, scene, at, group[k].start, radius);
    });
    if (free != nearest.end()) {
      out.push_back(std::move(group[*free]));
      group.erase(group.begin() + static_cast<std::ptrdiff_t>(*free));
      continue;
    }
    const std::optional<std::size_t> where =
        CheapestFreeInsertion(model, scene, group[nearest.front()], out, first, radius);
    if (!where) {
      return Error{"no collision-free move from scan " + std::to_string(out.size()) +
                   " to any of " + std::to_string(group.size()) +
                   " scans left, nor a place between two scans for the nearest (links as "
                   "capsules of " +
                   std::to_string(std::lround(radius * 1000)) + " mm)"};
    }
    out.insert(out.begin() + static_cast<std::ptrdiff_t>(*where),
               std::move(group[nearest.front()]));
    group.erase(group.begin() + static_cast<std::ptrdiff_t>(nearest.front()));
  }
  return OkStatus();
}

}  // namespace

Expected<ScanPlan> OrderForFreeMoves(const RobotModel& model, const Scene& scene, ScanPlan plan,
                                     double radius) {
  std::vector<PlannedScan> fit, validation;
  for (PlannedScan& scan : plan.scans)
    (scan.purpose == ScanPurpose::kFit ? fit : validation).push_back(std::move(scan));
  ScanPlan ordered;
  if (auto s = AppendNearestFirst(model, scene, std::move(fit), radius, ordered.scans); !s)
    return s.error();
  if (auto s = AppendNearestFirst(model, scene, std::move(validation), radius, ordered.scans); !s)
    return s.error();
  return ordered;
}

std::vector<std::size_t> BlockedMoves(const RobotModel& model, const Scene& scene,
                                      const ScanPlan& plan, double radius) {
  std::vector<std::size_t> blocked;
  for (std::size_t k = 1; k < plan.scans.size(); ++k) {
    if (!MoveIsFree(model, scene, plan.scans[k - 1].end, plan.scans[k].start, radius))
      blocked.push_back(k);
  }
  return blocked;
}

double JointTravel(const ScanPlan& plan) {
  double travel = 0;
  for (std::size_t s = 1; s < plan.scans.size(); ++s)
    travel += LargestJointDifference(plan.scans[s - 1].end, plan.scans[s].start);
  return travel;
}

double LidarJointSpeed(const SensorModel& lidar, double line_spacing) {
  return line_spacing * lidar.angle_increment / lidar.rotation_period;
}

Expected<ScanPlan> MakeScanPlan(const RobotModel& nominal, const SensorModel& sensor,
                                const Scene& scene, const PlanOptions& options) {
  // Views and sweeps aim the sensor's axis at the target from `distance`: that must lie within
  // the sensor's view range (along z for cameras and line scanners).
  if (options.kind != PlanOptions::Kind::kLidarSweeps &&
      (options.view.distance_min < sensor.range_min ||
       options.view.distance_max > sensor.range_max)) {
    return Error{"scan plan: view distance [" + std::to_string(options.view.distance_min) + ", " +
                 std::to_string(options.view.distance_max) +
                 "] m is outside the sensor's view range [" + std::to_string(sensor.range_min) +
                 ", " + std::to_string(sensor.range_max) + "] m"};
  }
  ScanPlan plan;
  const int total = options.fit_scans + options.validation_scans;
  for (int k = 0; k < total; ++k) {
    const bool fit = k < options.fit_scans;
    const int index_in_purpose = fit ? k : k - options.fit_scans;
    Random random(SubKey(options.seed, fit ? kFitLabel : kValidationLabel,
                         static_cast<std::uint64_t>(index_in_purpose)));
    std::optional<PlannedScan> scan;
    for (int attempt = 0; attempt < options.max_attempts && !scan; ++attempt) {
      switch (options.kind) {
        case PlanOptions::Kind::kStationaryViews:
          scan = TryStationary(nominal, scene, options, random);
          break;
        case PlanOptions::Kind::kLineSweeps:
          scan = TryLineSweep(nominal, scene, options, random);
          break;
        case PlanOptions::Kind::kLidarSweeps:
          scan = TryLidarSweep(nominal, scene, options, random);
          break;
      }
      // A sweep's links are checked along it; a stationary view's start is its end.
      if (scan && options.link_radius > 0 &&
          !MoveIsFree(nominal, scene, scan->start, scan->end, options.link_radius)) {
        scan.reset();
      }
    }
    if (!scan) {
      return Error{"scan plan: no feasible " + std::string(fit ? "fit" : "validation") + " scan " +
                   std::to_string(index_in_purpose) + " (plan index " + std::to_string(k) +
                   ") after " + std::to_string(options.max_attempts) +
                   " attempts; widen the view ranges or move the target"};
    }
    scan->purpose = fit ? ScanPurpose::kFit : ScanPurpose::kValidation;
    plan.scans.push_back(std::move(*scan));
  }
  if (options.link_radius > 0)
    return OrderForFreeMoves(nominal, scene, std::move(plan), options.link_radius);
  return plan;
}

}  // namespace selfcal::sim
