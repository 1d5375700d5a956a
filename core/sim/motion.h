// Joint-space motions of the simulated arm: straight lines in joint space with a trapezoidal
// speed profile (constant velocity between acceleration ramps), and a timeline of such moves.
#pragma once

#include <vector>

#include "core/model/robot_model.h"

namespace selfcal::sim {

class JointMove {
 public:
  // From `from` to `to`, starting at `start_time` [s]. The path parameter s in [0, 1] reaches
  // `peak_rate` [1/s] after accelerating at `acceleration` [1/s^2]; a move too short for the
  // peak rate has a triangular profile. `from == to` is a hold of `hold_duration` seconds.
  static JointMove Line(std::vector<double> from, std::vector<double> to, double start_time,
                        double peak_rate, double acceleration);
  static JointMove Hold(std::vector<double> at, double start_time, double hold_duration);
  // The fastest line within `fraction` of each joint's velocity and acceleration limits.
  static JointMove Transit(const RobotModel& model, std::vector<double> from,
                           std::vector<double> to, double start_time, double fraction);

  double start_time() const { return start_time_; }
  double end_time() const { return start_time_ + duration_; }
  double duration() const { return duration_; }
  const std::vector<double>& from() const { return from_; }
  const std::vector<double>& to() const { return to_; }

  // Joint positions and velocities at time t (held at the ends outside the move).
  void Evaluate(double t, double* positions, double* velocities) const;

 private:
  std::vector<double> from_, to_;
  double start_time_ = 0;
  double duration_ = 0;
  double ramp_ = 0;          // s, length of each acceleration ramp
  double peak_rate_ = 0;     // 1/s
  double acceleration_ = 0;  // 1/s^2
};

// Consecutive moves; Evaluate() picks the move that covers t.
class Timeline {
 public:
  void Append(JointMove move) { moves_.push_back(std::move(move)); }
  double end_time() const { return moves_.empty() ? 0.0 : moves_.back().end_time(); }
  const std::vector<double>& FinalPositions() const { return moves_.back().to(); }
  void Evaluate(double t, double* positions, double* velocities) const;
  bool empty() const { return moves_.empty(); }
  // The index of the move Evaluate() uses at t, and the moves.
  std::size_t MoveIndex(double t) const;
  const std::vector<JointMove>& moves() const { return moves_; }

 private:
  std::vector<JointMove> moves_;
};

}  // namespace selfcal::sim
