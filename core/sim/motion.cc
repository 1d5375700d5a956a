#include "core/sim/motion.h"

#include <algorithm>
#include <cmath>

namespace selfcal::sim {

JointMove JointMove::Line(std::vector<double> from, std::vector<double> to, double start_time,
                          double peak_rate, double acceleration) {
  JointMove move;
  move.from_ = std::move(from);
  move.to_ = std::move(to);
  move.start_time_ = start_time;
  move.acceleration_ = acceleration;
  if (peak_rate * peak_rate / acceleration <= 1.0) {
    move.peak_rate_ = peak_rate;
    move.ramp_ = peak_rate / acceleration;
    move.duration_ = 1.0 / peak_rate + move.ramp_;
  } else {
    move.ramp_ = std::sqrt(1.0 / acceleration);
    move.peak_rate_ = acceleration * move.ramp_;
    move.duration_ = 2 * move.ramp_;
  }
  return move;
}

JointMove JointMove::Hold(std::vector<double> at, double start_time, double hold_duration) {
  JointMove move;
  move.from_ = at;
  move.to_ = std::move(at);
  move.start_time_ = start_time;
  move.duration_ = hold_duration;
  return move;
}

JointMove JointMove::Transit(const RobotModel& model, std::vector<double> from,
                             std::vector<double> to, double start_time, double fraction) {
  double rate = 1e9, acceleration = 1e9;
  for (std::size_t j = 0; j < from.size(); ++j) {
    const double distance = std::abs(to[j] - from[j]);
    if (distance < 1e-12) continue;
    rate = std::min(rate, fraction * model.joints[j].max_velocity / distance);
    acceleration = std::min(acceleration, fraction * model.joints[j].max_acceleration / distance);
  }
  if (rate >= 1e9) return Hold(std::move(from), start_time, 0.0);
  return Line(std::move(from), std::move(to), start_time, rate, acceleration);
}

void JointMove::Evaluate(double t, double* positions, double* velocities) const {
  const double tau = std::clamp(t - start_time_, 0.0, duration_);
  double s = 0, rate = 0;
  if (peak_rate_ > 0) {
    if (tau < ramp_) {
      s = 0.5 * acceleration_ * tau * tau;
      rate = acceleration_ * tau;
    } else if (tau <= duration_ - ramp_) {
      s = 0.5 * acceleration_ * ramp_ * ramp_ + peak_rate_ * (tau - ramp_);
      rate = peak_rate_;
    } else {
      const double rest = duration_ - tau;
      s = 1.0 - 0.5 * acceleration_ * rest * rest;
      rate = acceleration_ * rest;
    }
  }
  for (std::size_t j = 0; j < from_.size(); ++j) {
    const double delta = to_[j] - from_[j];
    positions[j] = from_[j] + s * delta;
    if (velocities) velocities[j] = rate * delta;
  }
}

std::size_t Timeline::MoveIndex(double t) const {
  // The last move that starts at or before t.
  auto it = std::upper_bound(moves_.begin(), moves_.end(), t,
                             [](double time, const JointMove& m) { return time < m.start_time(); });
  return it == moves_.begin() ? 0 : static_cast<std::size_t>(it - moves_.begin()) - 1;
}

void Timeline::Evaluate(double t, double* positions, double* velocities) const {
  const JointMove& move = moves_[MoveIndex(t)];
  move.Evaluate(t, positions, velocities);
  if (velocities && (t < move.start_time() || t > move.end_time())) {
    for (std::size_t j = 0; j < move.from().size(); ++j) velocities[j] = 0;
  }
}

}  // namespace selfcal::sim
