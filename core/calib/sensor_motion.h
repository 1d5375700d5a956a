// How far a step of the parameters moves the sensor: the engine's convergence measure
// (docs/engine.md, deviation 18).
//
// The paper stops when |delta k_hat| <= epsilon. Where the model is parametrically singular that
// never happens: a sensor mounted with the tool's beta at -90 deg (a Hokuyo looking sideways)
// puts the tool's alpha and gamma about one axis, so only alpha - gamma reaches the sensor, and
// alpha + gamma drifts freely from iteration to iteration (measured on the field Hokuyo: at
// iteration 50 all but 7 % of |delta k_hat| lay along that one direction). This measure counts
// a step by what it does: the RMS over poses of the fit scans of the sensor pose's change, its
// position divided by s and its orientation in rad (the motion of a point at distance s, in
// k_hat's units, so that epsilon keeps its meaning), to first order. A direction that moves no
// sensor pose counts for nothing; a single MCPC parameter counts about as its own |delta|.
// Parameters beyond the MCPC chain (joint correction, intrinsics) count as in |delta k_hat|.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "core/calib/chain.h"
#include "core/calib/dataset.h"

namespace selfcal::calib {

class SensorMotion {
 public:
  // `free`: the indices into k_hat that the calibration moves. The poses are at most
  // kPosesPerScan of each fit scan, evenly spread.
  SensorMotion(const Chain& chain, const std::vector<std::size_t>& free,
               const std::vector<Dataset>& datasets);

  // The step from `before` to `after` (full k_hat vectors), linearized at `before`.
  double Step(const std::vector<double>& before, const std::vector<double>& after) const;
  // M over the free parameters at `k_hat`: Step(d)^2 = d^T M d for a step d of the free ones.
  Eigen::MatrixXd Metric(const std::vector<double>& k_hat) const;

  static constexpr std::size_t kPosesPerScan = 16;

 private:
  const Chain& chain_;
  const std::vector<std::size_t>& free_;
  std::vector<std::vector<double>> configurations_;  // joint positions [rad or m]
};

}  // namespace selfcal::calib
