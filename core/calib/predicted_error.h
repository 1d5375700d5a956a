// What a parameter covariance predicts for the sensor pose (core/calib/covariance.h computes
// it; CalibrationResult carries it). Apart from covariance.h so that calibrate.h needs no engine
// internals.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/model/evaluation.h"

namespace selfcal::calib {

// The sensor pose error a covariance predicts (1 sigma), over configurations: the position's
// sqrt(trace(J_p C J_p^T)) and the orientation's sqrt(trace(J_w C J_w^T)) at each; the same
// statistics as a measured error's.
using PredictedPoseError = PoseErrorStats;

// The predicted position error over the joint space: for each joint, its range [lower, upper]
// split into kErrorMapBins equal bins, and per bin the RMS over the configurations whose value
// of that joint falls in it (the other joints vary over the whole sample). A bin without
// configurations has samples 0 and RMS 0.
inline constexpr std::size_t kErrorMapBins = 6;
struct JointErrorProfile {
  std::string joint;       // the joint's name ("A4")
  bool prismatic = false;  // lower and upper in m, else rad
  double lower = 0, upper = 0;
  std::vector<std::size_t> samples;           // per bin
  std::vector<double> sensor_rms_position_m;  // per bin
  std::vector<double> flange_rms_position_m;  // per bin
};
// One bin of one joint, where the predicted sensor position error is largest.
struct ErrorRegion {
  std::size_t joint = 0, bin = 0;  // into PredictedErrorMap::joints and its bins
  double lower = 0, upper = 0;     // the bin's range, rad or m
  double sensor_rms_position_m = 0;
};
struct PredictedErrorMap {
  std::vector<JointErrorProfile> joints;
  // Each joint's worst bin, the largest sensor RMS first, at most kWorstRegions: which joint
  // ranges give the largest predicted error.
  std::vector<ErrorRegion> worst;
};
inline constexpr std::size_t kWorstRegions = 3;

struct PredictedError {
  std::size_t samples = 0;
  std::uint64_t seed = 0;
  PredictedPoseError sensor;
  // The robot's own geometry, as core/model/evaluation.h's `flange`: without the tool's
  // parameters (st(s_n)), whose errors that comparison takes from the truth.
  PredictedPoseError flange;
  PredictedErrorMap map;  // over the same configurations
};
// The configurations the engine predicts on: as many and drawn as `selfcal calibrate --truth`
// measures (RandomConfigurations of core/model/evaluation.h).
inline constexpr std::size_t kPredictionSamples = 500;
inline constexpr std::uint64_t kPredictionSeed = 1;

}  // namespace selfcal::calib
