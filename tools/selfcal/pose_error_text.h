// How the command line prints a pose error (core/model/evaluation.h): `evaluate`,
// `calibrate --truth` and `simulate` print the same sample set with the same digits, so one
// model pair gives one number wherever it is shown.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "core/model/evaluation.h"

namespace selfcal::cli {

// The configurations every command compares on unless told otherwise.
constexpr std::size_t kEvaluationSamples = 500;
constexpr std::uint64_t kEvaluationSeed = 1;

// "500 configurations (seed 1)".
std::string SampleSetText(std::size_t samples, std::uint64_t seed);

// "position rms    29.410 mm  max    57.841 mm   orientation rms   1.3414 deg  max   2.4687 deg".
std::string PoseErrorText(const PoseErrorStats& stats);

}  // namespace selfcal::cli
