// What the engine accepts for each of the paper's Table I parameters, in one place:
// CalibrationOptions::IsValid and the sensor-file reader (config/sensors/*.yaml) both check
// through these, and each names the value its own way ("g_min = 1.5, must be in [0, 1]";
// "key 'preprocessing.g_min' must be in [0, 1]"). Header-only, so that protocols/model_file checks
// a sensor file without linking the engine.
#pragma once

#include <cmath>

namespace selfcal::calib {

// A parameter's allowed values, and how an error states them ("must be " + requirement).
struct ParameterLimit {
  bool (*allows)(double value);
  const char* requirement;
};

// The noise/edge filter's window radii n and m (a (2n + 1) x (2m + 1) window).
inline constexpr ParameterLimit kFilterRadiusLimit{[](double v) { return v >= 0; }, "at least 0"};
// g_min: the fraction of valid neighbours the filter requires.
inline constexpr ParameterLimit kGMinLimit{[](double v) { return v >= 0 && v <= 1; }, "in [0, 1]"};
// d_max [m]: the farthest a matched pair may be apart.
inline constexpr ParameterLimit kDMaxLimit{[](double v) { return v > 0 && std::isfinite(v); },
                                           "positive and finite"};
// f_min: the least cosine between the normals of a matched pair.
inline constexpr ParameterLimit kFMinLimit{[](double v) { return v >= -1 && v <= 1; },
                                           "in [-1, 1]"};
// epsilon: the stop on |delta k| (0: stop by i_max only).
inline constexpr ParameterLimit kEpsilonLimit{[](double v) { return v >= 0 && std::isfinite(v); },
                                              "finite and not negative"};
// i_max: the most ICP iterations.
inline constexpr ParameterLimit kIMaxLimit{[](double v) { return v >= 1; }, "at least 1"};
// The query stride (docs/engine.md, deviation 11): every s-th grid row and column is matched.
inline constexpr ParameterLimit kQueryStrideLimit{[](double v) { return v >= 1; }, "at least 1"};
// The flying pixel angle [deg] (docs/engine.md, deviation 19): 0 = off.
inline constexpr ParameterLimit kFlyingPixelAngleLimit{[](double v) { return v >= 0 && v < 90; },
                                                       "in [0, 90) (0 = off)"};
// A sensor's latency against the joint states [s] (deviation 16's start value): milliseconds to a
// few hundred; a second is beyond any sensor, and "12" meant as milliseconds is caught.
inline constexpr ParameterLimit kLatencyLimit{[](double v) { return std::abs(v) <= 1.0; },
                                              "within +-1 s"};
// The uncertainty (1 sigma) of a held intrinsic: a relative scale, or an offset in m.
inline constexpr ParameterLimit kIntrinsicSdLimit{[](double v) { return v >= 0 && v <= 0.1; },
                                                  "in [0, 0.1]"};
inline constexpr ParameterLimit kLinkMarginLimit{[](double v) { return v >= 0 && v <= 0.2; },
                                                 "in [0, 0.2]"};

}  // namespace selfcal::calib
