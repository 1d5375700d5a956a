#include "core/trajectory/motion.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace selfcal::trajectory {
namespace {

// One phase of constant jerk.
struct Phase {
  double duration;
  double jerk;
};

// Scalar knots (time, s, ds/dt) of a profile.
struct ScalarKnot {
  double t, s, v;
};

// Integrates the phases from rest at s = 0 exactly.
std::vector<ScalarKnot> Integrate(const std::vector<Phase>& phases) {
  std::vector<ScalarKnot> knots = {{0, 0, 0}};
  double t = 0, s = 0, v = 0, a = 0;
  for (const Phase& p : phases) {
    if (p.duration <= 0) continue;
    const double h = p.duration;
    s += v * h + a * h * h / 2 + p.jerk * h * h * h / 6;
    v += a * h + p.jerk * h * h / 2;
    a += p.jerk * h;
    t += h;
    // A phase shorter than a microsecond (round-off of a phase that should be empty) would make
    // a knot interval so short that Hermite coefficients blow up: merge it into the last knot.
    if (t - knots.back().t < 1e-6 && knots.size() > 1) {
      knots.back() = {knots.back().t, s, v};
    } else {
      knots.push_back({t, s, v});
    }
  }
  return knots;
}

// Accelerating from rest to cruise speed `v` with acceleration <= a_max and jerk <= j_max
// (j_max = inf: trapezoid). Returns the phases and the distance covered.
std::vector<Phase> RampUp(double v, double a_max, double j_max, double& distance) {
  if (!std::isfinite(j_max)) {
    const double t = v / a_max;
    distance = v * t / 2;
    return {};  // trapezoids are built directly by Profile(): no jerk phases
  }
  const double a = std::min(a_max, std::sqrt(v * j_max));
  const double tj = a / j_max;
  const double ta = v / a - tj;  // >= 0 by construction of a
  distance = v * (v / a + tj) / 2;
  return {{tj, j_max}, {std::max(ta, 0.0), 0}, {tj, -j_max}};
}

// Builds the scalar profile rest -> cruise v (for cruise_time) -> rest. A trapezoid (infinite
// jerk) changes acceleration instantly: its knots are written directly.
std::vector<ScalarKnot> Profile(double v, double a_max, double j_max, double cruise_time) {
  if (!std::isfinite(j_max)) {
    const double ta = v / a_max;
    std::vector<ScalarKnot> knots = {{0, 0, 0}};
    const double d = v * ta / 2;
    knots.push_back({ta, d, v});
    if (cruise_time > 0) knots.push_back({ta + cruise_time, d + v * cruise_time, v});
    knots.push_back({2 * ta + cruise_time, 2 * d + v * cruise_time, 0});
    return knots;
  }
  double distance = 0;
  std::vector<Phase> phases = RampUp(v, a_max, j_max, distance);
  std::vector<Phase> all = phases;
  all.push_back({cruise_time, 0});
  for (const Phase& p : phases) all.push_back({p.duration, -p.jerk});
  return Integrate(all);
}

double RampDistance(double v, double a_max, double j_max) {
  double d = 0;
  RampUp(v, a_max, j_max, d);
  return d;
}

// Scales per-joint limits to limits of s for a line of per-joint lengths `delta`.
struct ScalarLimits {
  double v = std::numeric_limits<double>::infinity();
  double a = std::numeric_limits<double>::infinity();
  double j = std::numeric_limits<double>::infinity();
  Eigen::Index v_joint = 0;
};

ScalarLimits ScaleLimits(const Eigen::VectorXd& delta, const JointLimits& limits) {
  ScalarLimits s;
  for (Eigen::Index i = 0; i < delta.size(); ++i) {
    const double d = std::abs(delta[i]);
    if (d == 0) continue;
    if (limits.max_velocity[i] / d < s.v) {
      s.v = limits.max_velocity[i] / d;
      s.v_joint = i;
    }
    s.a = std::min(s.a, limits.max_acceleration[i] / d);
    if (limits.max_jerk.size() == delta.size()) s.j = std::min(s.j, limits.max_jerk[i] / d);
  }
  return s;
}

// `end`, when given, is where the last knot is pinned: origin + delta can differ from the goal
// by round-off, and the next motion of a program starts exactly at the goal.
Expected<JointTrajectory> ToJoints(const std::vector<ScalarKnot>& profile,
                                   const Eigen::VectorXd& origin, const Eigen::VectorXd& delta,
                                   const Eigen::VectorXd* end = nullptr) {
  std::vector<Knot> knots;
  knots.reserve(profile.size());
  for (const ScalarKnot& k : profile) {
    knots.push_back({k.t, origin + k.s * delta, k.v * delta});
  }
  if (end) knots.back().position = *end;
  // Exactly at rest at both ends (no round-off velocity).
  knots.front().velocity.setZero();
  knots.back().velocity.setZero();
  return JointTrajectory::FromKnots(std::move(knots));
}

Status CheckConfiguration(const Eigen::VectorXd& q, const JointLimits& limits, const char* what) {
  if (static_cast<std::size_t>(q.size()) != limits.size()) {
    return Error{std::string(what) + " has " + std::to_string(q.size()) + " joints, the robot " +
                 std::to_string(limits.size())};
  }
  if (!q.allFinite()) return Error{std::string(what) + " is not finite"};
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    if (q[i] < limits.lower[i] || q[i] > limits.upper[i]) {
      std::ostringstream s;
      s << what << ": joint " << i << " at " << q[i] << " rad is outside [" << limits.lower[i]
        << ", " << limits.upper[i] << "]";
      return Error{s.str()};
    }
  }
  return OkStatus();
}

}  // namespace

JointTrajectory Hold(const Eigen::VectorXd& position, double duration) {
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(position.size());
  return JointTrajectory::FromKnots({{0, position, zero}, {duration, position, zero}}).value();
}

Expected<JointTrajectory> PointToPoint(const Eigen::VectorXd& from, const Eigen::VectorXd& to,
                                       const JointLimits& limits) {
  if (auto s = CheckConfiguration(from, limits, "start"); !s.ok()) return s.error();
  if (auto s = CheckConfiguration(to, limits, "goal"); !s.ok()) return s.error();
  const Eigen::VectorXd delta = to - from;
  if (delta.cwiseAbs().maxCoeff() < 1e-12) return Hold(from, 1e-3);
  const ScalarLimits s = ScaleLimits(delta, limits);
  // Highest cruise speed whose ramps fit into the unit distance (bisection: the ramp distance
  // grows monotonically with the speed).
  double v = s.v;
  if (2 * RampDistance(v, s.a, s.j) > 1.0) {
    double low = 0, high = v;
    for (int i = 0; i < 100; ++i) {
      const double mid = (low + high) / 2;
      (2 * RampDistance(mid, s.a, s.j) > 1.0 ? high : low) = mid;
    }
    v = low;
  }
  const double cruise = std::max(0.0, (1.0 - 2 * RampDistance(v, s.a, s.j)) / v);
  auto profile = Profile(v, s.a, s.j, cruise);
  // Round-off: the integrated end lands within ~1e-15 of 1; pin it.
  profile.back().s = 1.0;
  return ToJoints(profile, from, delta, &to);
}

Expected<Sweep> ConstantVelocitySweep(const Eigen::VectorXd& from, const Eigen::VectorXd& to,
                                      double speed, const JointLimits& limits) {
  if (auto s = CheckConfiguration(from, limits, "sweep start"); !s.ok()) return s.error();
  if (auto s = CheckConfiguration(to, limits, "sweep end"); !s.ok()) return s.error();
  const Eigen::VectorXd delta = to - from;
  const double length = delta.cwiseAbs().maxCoeff();
  if (length < 1e-9) return Error{"sweep from and to are the same configuration"};
  if (!(speed > 0) || !std::isfinite(speed)) return Error{"sweep speed must be positive"};
  const ScalarLimits s = ScaleLimits(delta, limits);
  const double v = speed / length;  // in s units per second
  if (v > s.v * (1 + 1e-12)) {
    std::ostringstream m;
    m << "sweep speed " << speed << " rad/s needs joint " << s.v_joint << " at "
      << std::abs(delta[s.v_joint]) * v << " rad/s, above its limit "
      << limits.max_velocity[s.v_joint] << " rad/s";
    return Error{m.str()};
  }
  const double run_up = RampDistance(v, s.a, s.j);  // in s units
  const Eigen::VectorXd start = from - run_up * delta;
  const Eigen::VectorXd stop = to + run_up * delta;
  if (auto c = CheckConfiguration(start, limits, "sweep run-up start"); !c.ok()) return c.error();
  if (auto c = CheckConfiguration(stop, limits, "sweep run-out end"); !c.ok()) return c.error();
  auto profile = Profile(v, s.a, s.j, 1.0 / v);
  // Shift s so that the profile starts at -run_up; the cruise covers [0, 1] exactly.
  for (ScalarKnot& k : profile) k.s -= run_up;
  profile.back().s = 1.0 + run_up;
  auto trajectory = ToJoints(profile, from, delta);
  if (!trajectory.ok()) return trajectory.error();
  Sweep sweep;
  sweep.trajectory = std::move(*trajectory);
  // The cruise knots: the profile's time where s passes 0 and 1.
  for (const ScalarKnot& k : profile) {
    if (std::abs(k.s) < 1e-9) sweep.constant_begin = k.t;
    if (std::abs(k.s - 1.0) < 1e-9) sweep.constant_end = k.t;
  }
  return sweep;
}

}  // namespace selfcal::trajectory
