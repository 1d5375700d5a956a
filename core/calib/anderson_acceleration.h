// Anderson acceleration of ICP's fixed-point iteration (docs/engine.md, deviation 18).
//
// One ICP iteration is a map k <- G(k): match at k, then solve. Where re-matching converges
// slowly, G contracts by little per iteration (measured on the field Hokuyo: the step shrank by
// 0.94 per iteration, about 40 iterations to epsilon); the paper's loop then ends at i_max.
// Anderson's method (type II, as in Zhang, Peng, Hou and Deng, "Fast and robust iterative
// closest point", 2021) takes the next point as the combination of the last m + 1 values of G
// whose residuals G(k) - k combine to the smallest, measured in the sensor-motion metric
// (sensor_motion.h). Two guards, because G is only piecewise smooth (the matches change) and
// an extrapolation far from the fixed point can jump to another local minimum (seen on a
// kinect-bunny twin: 0.42 mm with the plain loop, 62 mm with acceleration from iteration 2):
// - It waits for the linear regime that it is made for: it combines only points of a run of
//   kContracting plain ICP steps each shorter than the one before.
// - An accelerated point whose ICP step turns out longer than the step before it, or at which
//   fewer scans' points find a match (below kMatchShare of the matches at the point before it),
//   is dropped, and the loop goes on from the last plain G value with an empty history (and
//   waits again). The matches: on a kinect-office twin with every effect, 60 mm off, the plain
//   steps shrank slowly while ICP pulled the scans in (0.77 -> 1.35 M matches); accelerated
//   points there had 1.03 M, then 0.42 M, 0.19 M matches, the steps stayed short, and the loop
//   slid off to 126 mm (the plain loop: 15 mm). Overlap that the point loses is a step away
//   from the fixed point however short the step.
// A point that was accelerated but never matched is never a result (Settled()).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <deque>
#include <vector>

namespace selfcal::calib {

class AndersonAcceleration {
 public:
  // `memory`: m, the past residuals combined (0: off, Next returns g); `free`: the indices into
  // k_hat the calibration moves; `metric`: the inner product of the residuals over them;
  // `lower`: their least values (empty = none), which an accelerated point is kept to.
  AndersonAcceleration(int memory, std::vector<std::size_t> free, Eigen::MatrixXd metric,
                       std::vector<double> lower = {});

  // After the ICP iteration from `x` to `g = G(x)` whose step measured `step`, with `matches`
  // valid matches at x: where to match next (g, or the accelerated point).
  std::vector<double> Next(const std::vector<double>& x, std::vector<double> g, double step,
                           std::size_t matches);
  // What the calibration returns when it stops at `k_hat`: the last G value if `k_hat` is the
  // accelerated point Next returned last (it was never matched and solved), else `k_hat`.
  std::vector<double> Settled(std::vector<double> k_hat) const;

  // Plain steps, each shorter than the one before, before the first accelerated point.
  static constexpr int kContracting = 3;
  // The share of the matches at the point before that an accelerated point must keep.
  static constexpr double kMatchShare = 0.98;

  int accelerated() const { return accelerated_; }  // points taken
  int rejected() const { return rejected_; }        // ... of them dropped by the safeguard

 private:
  Eigen::VectorXd FreeOf(const std::vector<double>& k) const;
  void Restart();

  std::size_t memory_;
  std::vector<std::size_t> free_;
  Eigen::MatrixXd metric_;
  std::vector<double> lower_;
  std::deque<Eigen::VectorXd> x_, g_;  // the last memory + 1 points and their G values
  std::vector<double> last_g_;         // the last plain ICP result
  std::vector<double> handed_out_;     // the last accelerated point Next returned
  bool at_accelerated_ = false;        // the point handed out last was accelerated
  double last_step_ = 0;               // the step of the ICP iteration before it
  std::size_t last_matches_ = 0;       // ... and its valid matches
  int contracting_ = 0;                // plain steps in a row, each shorter than the one before
  int accelerated_ = 0, rejected_ = 0;
};

}  // namespace selfcal::calib
