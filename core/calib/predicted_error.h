// What a parameter covariance predicts for the sensor pose (core/calib/covariance.h computes
// it; CalibrationResult carries it). Apart from covariance.h so that calibrate.h needs no engine
// internals.
#pragma once

#include <cstddef>
#include <cstdint>

namespace selfcal::calib {

// The sensor pose error a covariance predicts (1 sigma), over configurations: the position's
// sqrt(trace(J_p C J_p^T)) and the orientation's sqrt(trace(J_w C J_w^T)) at each.
struct PredictedPoseError {
  double rms_position_m = 0, max_position_m = 0;
  double rms_orientation_rad = 0, max_orientation_rad = 0;
};
struct PredictedError {
  std::size_t samples = 0;
  std::uint64_t seed = 0;
  PredictedPoseError sensor;
  // The robot's own geometry, as core/model/evaluation.h's `flange`: without the tool's
  // parameters (st(s_n)), whose errors that comparison takes from the truth.
  PredictedPoseError flange;
};
// The configurations the engine predicts on: as many and drawn as `selfcal calibrate --truth`
// measures (RandomConfigurations of core/model/evaluation.h).
inline constexpr std::size_t kPredictionSamples = 500;
inline constexpr std::uint64_t kPredictionSeed = 1;

}  // namespace selfcal::calib
