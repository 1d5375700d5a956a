#include "daemon/plan.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "protocols/model_file/yaml_reader.h"

namespace selfcal::daemon {

Expected<ScanPlan> ParseScanPlan(const std::string& text, const std::string& path) {
  return yaml::Catching<ScanPlan>([&] {
    ScanPlan plan;
    yaml::StrictMap root(yaml::LoadString(text, path), "", path);
    plan.name = root.Required<std::string>("name");
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

Motion PlanMotion(const std::vector<double>& from, const std::vector<double>& to,
                  const RobotModel& model, double fraction, double speed_cap) {
  Motion motion{from, to, 0.0};
  // Profile of s in [0, 1] over T with ta = T/4: peak speed 4/(3T), acceleration 16/(3T^2).
  for (std::size_t j = 0; j < from.size() && j < model.joints.size(); ++j) {
    const double distance = std::abs(to[j] - from[j]);
    if (distance == 0) continue;
    double v = model.joints[j].max_velocity * fraction;
    if (speed_cap > 0) v = std::min(v, speed_cap);
    const double a = model.joints[j].max_acceleration * fraction;
    motion.duration =
        std::max({motion.duration, 4 * distance / (3 * v), std::sqrt(16 * distance / (3 * a))});
  }
  return motion;
}

Motion PlanSweep(const PlannedScan& scan, const RobotModel& model) {
  return PlanMotion(scan.from, scan.to, model, 1.0, scan.speed);
}

std::vector<double> Motion::At(double t) const {
  double s = 1;
  if (duration > 0 && t < duration) {
    const double T = duration, ta = T / 4, v = 4 / (3 * T), a = v / ta;
    if (t <= 0)
      s = 0;
    else if (t < ta)
      s = 0.5 * a * t * t;
    else if (t < T - ta)
      s = 0.5 * a * ta * ta + v * (t - ta);
    else
      s = 1 - 0.5 * a * (T - t) * (T - t);
  }
  std::vector<double> q(from.size());
  for (std::size_t j = 0; j < q.size(); ++j) q[j] = from[j] + s * (to[j] - from[j]);
  return q;
}

}  // namespace selfcal::daemon
