#include "core/trajectory/joint_trajectory.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace selfcal::trajectory {

JointLimits LimitsFromModel(const RobotModel& model, double fraction) {
  const auto n = static_cast<Eigen::Index>(model.JointCount());
  JointLimits limits;
  limits.lower.resize(n);
  limits.upper.resize(n);
  limits.max_velocity.resize(n);
  limits.max_acceleration.resize(n);
  limits.max_jerk.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const JointSpec& joint = model.joints[static_cast<std::size_t>(i)];
    limits.lower[i] = joint.lower;
    limits.upper[i] = joint.upper;
    limits.max_velocity[i] = joint.max_velocity * fraction;
    limits.max_acceleration[i] = joint.max_acceleration * fraction;
    limits.max_jerk[i] = limits.max_acceleration[i] / kDefaultJerkTime;
  }
  return limits;
}

namespace {

// Hermite coefficients of one joint over a segment of length h: p(u) = c0 + c1 u + c2 u^2 + c3 u^3
// with u = t - t0 in seconds.
struct Cubic {
  double c0, c1, c2, c3;
  double P(double u) const { return c0 + u * (c1 + u * (c2 + u * c3)); }
  double V(double u) const { return c1 + u * (2 * c2 + u * 3 * c3); }
  double A(double u) const { return 2 * c2 + 6 * c3 * u; }
};

Cubic MakeCubic(double p0, double v0, double p1, double v1, double h) {
  const double dp = p1 - p0;
  return {p0, v0, (3 * dp / h - 2 * v0 - v1) / h, (-2 * dp / h + v0 + v1) / (h * h)};
}

std::string JointName(const std::vector<std::string>& names, Eigen::Index i) {
  const auto index = static_cast<std::size_t>(i);
  return index < names.size() ? names[index] : "joint " + std::to_string(i);
}

}  // namespace

Expected<JointTrajectory> JointTrajectory::FromKnots(std::vector<Knot> knots) {
  if (knots.empty()) return Error{"trajectory has no knots"};
  const Eigen::Index n = knots.front().position.size();
  if (n == 0) return Error{"trajectory knot 0 has no joints"};
  for (std::size_t k = 0; k < knots.size(); ++k) {
    const Knot& knot = knots[k];
    const std::string where = "trajectory knot " + std::to_string(k);
    if (knot.position.size() != n || knot.velocity.size() != n) {
      return Error{where + ": " + std::to_string(knot.position.size()) + " positions and " +
                   std::to_string(knot.velocity.size()) + " velocities, expected " +
                   std::to_string(n)};
    }
    if (!std::isfinite(knot.time) || !knot.position.allFinite() || !knot.velocity.allFinite()) {
      return Error{where + ": not a finite number"};
    }
    if (k == 0 && knot.time != 0.0) return Error{where + ": the first knot must be at time 0"};
    if (k > 0 && !(knot.time > knots[k - 1].time)) {
      return Error{where + ": time " + std::to_string(knot.time) + " s does not increase after " +
                   std::to_string(knots[k - 1].time) + " s"};
    }
  }
  JointTrajectory trajectory;
  trajectory.knots_ = std::move(knots);
  return trajectory;
}

Sample JointTrajectory::Evaluate(double time) const {
  Sample sample;
  const auto n = static_cast<Eigen::Index>(joint_count());
  sample.acceleration = Eigen::VectorXd::Zero(n);
  if (time <= 0.0 || knots_.size() == 1) {
    sample.position = knots_.front().position;
    sample.velocity = knots_.size() == 1 ? Eigen::VectorXd::Zero(n) : knots_.front().velocity;
    if (time < 0.0) sample.velocity.setZero();
    return sample;
  }
  if (time >= duration()) {
    sample.position = knots_.back().position;
    sample.velocity = Eigen::VectorXd::Zero(n);
    if (time == duration()) sample.velocity = knots_.back().velocity;
    return sample;
  }
  // The segment [t_k, t_k+1) that holds `time`.
  const auto it = std::upper_bound(knots_.begin(), knots_.end(), time,
                                   [](double t, const Knot& knot) { return t < knot.time; });
  const Knot& b = *it;
  const Knot& a = *(it - 1);
  const double h = b.time - a.time;
  const double u = time - a.time;
  sample.position.resize(n);
  sample.velocity.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Cubic c = MakeCubic(a.position[i], a.velocity[i], b.position[i], b.velocity[i], h);
    sample.position[i] = c.P(u);
    sample.velocity[i] = c.V(u);
    sample.acceleration[i] = c.A(u);
  }
  return sample;
}

Status JointTrajectory::Append(const JointTrajectory& next, double tolerance) {
  if (next.knots_.empty()) return OkStatus();
  if (knots_.empty()) {
    knots_ = next.knots_;
    return OkStatus();
  }
  const Knot& last = knots_.back();
  const Knot& first = next.knots_.front();
  if (first.position.size() != last.position.size()) {
    return Error{"cannot append a trajectory of " + std::to_string(first.position.size()) +
                 " joints to one of " + std::to_string(last.position.size())};
  }
  const double position_gap = (first.position - last.position).cwiseAbs().maxCoeff();
  const double velocity_gap = (first.velocity - last.velocity).cwiseAbs().maxCoeff();
  if (position_gap > tolerance || velocity_gap > tolerance) {
    return Error{"cannot append: the next trajectory starts " + std::to_string(position_gap) +
                 " rad and " + std::to_string(velocity_gap) + " rad/s away from our end"};
  }
  const double offset = last.time;
  for (std::size_t k = 1; k < next.knots_.size(); ++k) {
    Knot knot = next.knots_[k];
    knot.time += offset;
    knots_.push_back(std::move(knot));
  }
  return OkStatus();
}

Status CheckLimits(const JointTrajectory& trajectory, const JointLimits& limits,
                   const std::vector<std::string>& joint_names, double tolerance) {
  const auto n = static_cast<Eigen::Index>(trajectory.joint_count());
  if (static_cast<Eigen::Index>(limits.size()) != n) {
    return Error{"trajectory has " + std::to_string(n) + " joints, the robot " +
                 std::to_string(limits.size())};
  }
  const auto& knots = trajectory.knots();
  auto fail = [&](Eigen::Index i, std::size_t segment, double time, const std::string& what) {
    std::ostringstream s;
    s << JointName(joint_names, i) << " at t=" << time << " s (segment " << segment
      << "): " << what;
    return Error{s.str()};
  };
  auto check_position = [&](Eigen::Index i, std::size_t segment, double time, double p) -> Status {
    const double span = limits.upper[i] - limits.lower[i];
    if (p < limits.lower[i] - tolerance * span || p > limits.upper[i] + tolerance * span) {
      std::ostringstream s;
      s << "position " << p << " rad outside [" << limits.lower[i] << ", " << limits.upper[i]
        << "]";
      return fail(i, segment, time, s.str());
    }
    return OkStatus();
  };
  for (Eigen::Index i = 0; i < n; ++i) {
    const double vmax = limits.max_velocity[i] * (1 + tolerance);
    const double amax = limits.max_acceleration[i] * (1 + tolerance);
    if (auto s = check_position(i, 0, 0.0, knots.front().position[i]); !s.ok()) return s;
    if (std::abs(knots.front().velocity[i]) > vmax) {
      return fail(i, 0, 0.0,
                  "velocity " + std::to_string(knots.front().velocity[i]) +
                      " rad/s above the limit " + std::to_string(limits.max_velocity[i]));
    }
    for (std::size_t k = 0; k + 1 < knots.size(); ++k) {
      const Knot& a = knots[k];
      const Knot& b = knots[k + 1];
      const double h = b.time - a.time;
      const Cubic c = MakeCubic(a.position[i], a.velocity[i], b.position[i], b.velocity[i], h);
      // Candidate times: both ends and the zeros of the velocity (position extrema), the zero
      // of the acceleration (velocity extremum).
      std::vector<double> position_times = {0.0, h};
      const double qa = 3 * c.c3, qb = 2 * c.c2, qc = c.c1;
      if (std::abs(qa) > 1e-15) {
        const double disc = qb * qb - 4 * qa * qc;
        if (disc >= 0) {
          const double r = std::sqrt(disc);
          position_times.push_back((-qb + r) / (2 * qa));
          position_times.push_back((-qb - r) / (2 * qa));
        }
      } else if (std::abs(qb) > 1e-15) {
        position_times.push_back(-qc / qb);
      }
      for (double u : position_times) {
        if (u < 0 || u > h) continue;
        if (auto s = check_position(i, k, a.time + u, c.P(u)); !s.ok()) return s;
      }
      std::vector<double> velocity_times = {0.0, h};
      if (std::abs(c.c3) > 1e-15) velocity_times.push_back(-c.c2 / (3 * c.c3));
      for (double u : velocity_times) {
        if (u < 0 || u > h) continue;
        if (std::abs(c.V(u)) > vmax) {
          return fail(i, k, a.time + u,
                      "velocity " + std::to_string(c.V(u)) + " rad/s above the limit " +
                          std::to_string(limits.max_velocity[i]));
        }
      }
      for (double u : {0.0, h}) {
        if (std::abs(c.A(u)) > amax) {
          return fail(i, k, a.time + u,
                      "acceleration " + std::to_string(c.A(u)) + " rad/s^2 above the limit " +
                          std::to_string(limits.max_acceleration[i]));
        }
      }
    }
  }
  return OkStatus();
}

double MaxJerk(const JointTrajectory& trajectory) {
  double jerk = 0.0;
  const auto& knots = trajectory.knots();
  for (std::size_t k = 0; k + 1 < knots.size(); ++k) {
    const double h = knots[k + 1].time - knots[k].time;
    for (Eigen::Index i = 0; i < knots[k].position.size(); ++i) {
      const Cubic c = MakeCubic(knots[k].position[i], knots[k].velocity[i],
                                knots[k + 1].position[i], knots[k + 1].velocity[i], h);
      jerk = std::max(jerk, std::abs(6 * c.c3));
    }
  }
  return jerk;
}

}  // namespace selfcal::trajectory
