#include "daemon/plan.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "core/trajectory/motion.h"
#include "protocols/model_file/yaml_reader.h"

namespace selfcal::daemon {

const char* PlanModeName(PlanMode mode) {
  return mode == PlanMode::kRemaster ? "remaster" : "full";
}

Expected<ScanPlan> ParseScanPlan(const std::string& text, const std::string& path) {
  return yaml::Catching<ScanPlan>([&] {
    ScanPlan plan;
    yaml::StrictMap root(yaml::LoadString(text, path), "", path);
    plan.name = root.Required<std::string>("name");
    const auto mode = root.Optional<std::string>("mode", "full");
    if (mode != "full" && mode != "remaster") root.Fail("mode", "must be full or remaster");
    plan.mode = mode == "remaster" ? PlanMode::kRemaster : PlanMode::kFull;
    const auto scans = root.Sequence("scans");
    for (std::size_t i = 0; i < scans.size(); ++i) {
      yaml::StrictMap scan(scans[i], "scans[" + std::to_string(i) + "]", path);
      PlannedScan planned;
      const auto purpose = scan.Required<std::string>("purpose");
      if (purpose != "fit" && purpose != "validation")
        scan.Fail("purpose", "must be fit or validation");
      planned.validation = purpose == "validation";
      planned.from = scan.Required<std::vector<double>>("from");
      planned.to = scan.Required<std::vector<double>>("to");
      planned.speed = scan.Required<double>("speed");
      if (!(planned.speed > 0)) scan.Fail("speed", "must be positive");
      scan.RejectUnknownKeys();
      plan.scans.push_back(std::move(planned));
    }
    root.RejectUnknownKeys();
    return plan;
  });
}

Expected<ScanPlan> ReadScanPlan(const std::string& path) {
  return yaml::Catching<ScanPlan>([&] {
    std::ostringstream text;
    text << yaml::LoadFile(path);
    auto plan = ParseScanPlan(text.str(), path);
    if (!plan) throw yaml::ParseError(plan.error().message);
    return std::move(plan).value();
  });
}

namespace {

std::string Joints(const std::vector<double>& q) {
  std::ostringstream out;
  out << std::setprecision(17) << "[";
  for (std::size_t j = 0; j < q.size(); ++j) out << (j ? ", " : "") << q[j];
  out << "]";
  return out.str();
}

}  // namespace

std::string FormatScanPlan(const ScanPlan& plan, const std::string& comment) {
  std::ostringstream text;
  text << "# " << comment << "\n";
  text << "name: " << plan.name << "\n";
  if (plan.mode == PlanMode::kRemaster) {
    text << "mode: remaster  # only the joints' zero offsets and the sensor mount (selfcald)\n";
  }
  text << "scans:\n";
  for (const auto& scan : plan.scans) {
    text << "  - {purpose: " << (scan.validation ? "validation" : "fit")
         << ", from: " << Joints(scan.from) << ", to: " << Joints(scan.to)
         << ", speed: " << std::setprecision(17) << scan.speed << "}\n";
  }
  return text.str();
}

ScanPlan FromSimulatedPlan(const std::string& name, const sim::ScanPlan& plan) {
  ScanPlan out;
  out.name = name;
  for (const auto& scan : plan.scans) {
    double travel = 0;
    for (std::size_t j = 0; j < scan.start.size(); ++j)
      travel = std::max(travel, std::abs(scan.end[j] - scan.start[j]));
    const double speed = scan.peak_rate > 0 && travel > 0 ? scan.peak_rate * travel : 0.1;
    out.scans.push_back(
        {scan.purpose == sim::ScanPurpose::kValidation, scan.start, scan.end, speed});
  }
  return out;
}

sim::ScanPlan ToSimulatedPlan(const ScanPlan& plan) {
  sim::ScanPlan out;
  for (const auto& scan : plan.scans) {
    sim::PlannedScan planned;
    planned.purpose = scan.validation ? sim::ScanPurpose::kValidation : sim::ScanPurpose::kFit;
    planned.start = scan.from;
    planned.end = scan.to;
    double travel = 0;
    int moving = 0;
    for (std::size_t j = 0; j < scan.from.size() && j < scan.to.size(); ++j) {
      const double distance = std::abs(scan.to[j] - scan.from[j]);
      if (distance > 0) ++moving, planned.moving_joint = static_cast<int>(j);
      travel = std::max(travel, distance);
    }
    if (moving != 1) planned.moving_joint = -1;
    planned.peak_rate = travel > 0 ? scan.speed / travel : 0.0;
    out.scans.push_back(std::move(planned));
  }
  return out;
}

std::string CheckPlan(const ScanPlan& plan, const RobotModel& model, double margin) {
  const std::size_t n = model.JointCount();
  bool fit = false, validation = false;
  for (std::size_t i = 0; i < plan.scans.size(); ++i) {
    const auto& scan = plan.scans[i];
    (scan.validation ? validation : fit) = true;
    for (const auto* waypoint : {&scan.from, &scan.to}) {
      const char* which = waypoint == &scan.from ? "from" : "to";
      if (waypoint->size() != n) {
        return "plan " + plan.name + ": scan " + std::to_string(i) + " '" + which + "' has " +
               std::to_string(waypoint->size()) + " joints, the robot has " + std::to_string(n);
      }
      for (std::size_t j = 0; j < n; ++j) {
        const auto& joint = model.joints[j];
        const double q = (*waypoint)[j];
        if (!std::isfinite(q) || q < joint.lower + margin || q > joint.upper - margin) {
          std::ostringstream out;
          out << "plan " << plan.name << ": scan " << i << " '" << which << "' joint " << joint.name
              << " = " << q << " is outside the limits [" << joint.lower << ", " << joint.upper
              << "] less a margin of " << margin;
          return out.str();
        }
      }
    }
    for (std::size_t j = 0; j < n; ++j) {
      if (scan.from[j] != scan.to[j] && scan.speed > model.joints[j].max_velocity) {
        std::ostringstream out;
        out << "plan " << plan.name << ": scan " << i << " speed " << scan.speed
            << " exceeds the velocity limit " << model.joints[j].max_velocity << " of joint "
            << model.joints[j].name;
        return out.str();
      }
    }
  }
  if (!fit) return "plan " + plan.name + " has no fit scan";
  if (!validation)
    return "plan " + plan.name + " has no validation scan (the acceptance gate needs one)";
  return {};
}

namespace {

Eigen::VectorXd ToVector(const std::vector<double>& q) {
  return Eigen::Map<const Eigen::VectorXd>(q.data(), static_cast<Eigen::Index>(q.size()));
}

// Appends `next`, which starts where `program` ends, and returns the time at which it started.
Expected<double> Append(trajectory::JointTrajectory& program,
                        const Expected<trajectory::JointTrajectory>& next,
                        const std::string& what) {
  if (!next) return Error{what + ": " + next.error().message};
  const double start = program.duration();
  if (auto appended = program.Append(*next); !appended) {
    return Error{what + ": " + appended.error().message};
  }
  return start;
}

}  // namespace

Expected<trajectory::JointTrajectory> PlanSweep(const PlannedScan& scan, const RobotModel& model,
                                                double settle_time) {
  const Eigen::VectorXd from = ToVector(scan.from), to = ToVector(scan.to);
  if (from == to) return trajectory::Hold(from, std::max(settle_time, 1e-3));
  trajectory::JointLimits limits = trajectory::LimitsFromModel(model, 1.0);
  // The same cap for every joint: the joint that travels the most reaches `speed`.
  limits.max_velocity = limits.max_velocity.cwiseMin(scan.speed);
  return trajectory::PointToPoint(from, to, limits);
}

Expected<ScanMotion> PlanScanMotion(const ScanPlan& plan, const std::vector<double>& start,
                                    const RobotModel& model, double speed_fraction,
                                    double settle_time) {
  const trajectory::JointLimits move_limits = trajectory::LimitsFromModel(model, speed_fraction);
  ScanMotion motion;
  Eigen::VectorXd at = ToVector(start);
  motion.trajectory = trajectory::Hold(at, 1e-3);
  for (std::size_t i = 0; i < plan.scans.size(); ++i) {
    const auto& scan = plan.scans[i];
    const std::string what = "plan " + plan.name + ": scan " + std::to_string(i);
    ScanTiming timing{static_cast<int>(i), scan.validation, 0, 0, 0};
    auto move = Append(motion.trajectory,
                       trajectory::PointToPoint(at, ToVector(scan.from), move_limits), what);
    if (!move) return move.error();
    timing.move_begin = *move;
    at = ToVector(scan.from);
    if (settle_time > 0) {
      if (auto s = Append(motion.trajectory, trajectory::Hold(at, settle_time), what); !s)
        return s.error();
    }
    auto sweep = Append(motion.trajectory, PlanSweep(scan, model, settle_time), what);
    if (!sweep) return sweep.error();
    timing.begin = *sweep;
    timing.end = motion.trajectory.duration();
    at = ToVector(scan.to);
    if (settle_time > 0) {
      if (auto s = Append(motion.trajectory, trajectory::Hold(at, settle_time), what); !s)
        return s.error();
    }
    motion.scans.push_back(timing);
  }
  return motion;
}

}  // namespace selfcal::daemon
