// Comparison of a kinematic model against a reference ("truth") over random configurations, as
// the paper evaluates calibrations ("Evaluation"): position and orientation error of the end
// effector pose over configurations drawn within the joint limits. The one home of the sensor
// pose error: `selfcal evaluate`, `selfcal calibrate --truth`, the simulator's ground truth and
// the engine's tests all measure with SensorPoseError().
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/model/robot_model.h"

namespace selfcal {

// Position error |t_truth - t_model| and orientation error (angle of R_truth^T R_model) of
// T_base_sensor, RMS and maximum over the configurations.
struct PoseErrorStats {
  double rms_position_m = 0;
  double max_position_m = 0;
  double rms_orientation_rad = 0;
  double max_orientation_rad = 0;
};

struct ModelComparison {
  std::size_t samples = 0;
  std::uint64_t seed = 0;
  // T_base_sensor of `model` against T_base_sensor of `truth`.
  PoseErrorStats sensor;
  // The paper's protocol for comparing a self-calibration with a reference calibration: the
  // parameters the model cannot calibrate are taken from the truth before comparing. That is the
  // last transform st(s_n) (joint n to sensor), the base st(s_0), and every other parameter the
  // model's mask leaves out (J1 -> J2 beta and y with the default mask). What remains is the error
  // of the robot's own calibrated geometry, measured at the truth's sensor frame.
  PoseErrorStats flange;
};

// T_base_sensor of `model` against `truth`'s at every configuration (n joint positions each).
// The models must have the same joints (CheckComparable). No configurations: all zero.
PoseErrorStats SensorPoseError(const RobotModel& truth, const RobotModel& model,
                               std::span<const std::vector<double>> configurations);

// The same over `samples` configurations drawn uniformly within the truth's joint limits
// (RandomConfigurations(truth, samples, seed)).
PoseErrorStats SensorPoseError(const RobotModel& truth, const RobotModel& model,
                               std::size_t samples, std::uint64_t seed);

// Empty when `truth` and `model` can be compared (same joint count, names and types), else why not.
std::string CheckComparable(const RobotModel& truth, const RobotModel& model);

// Draws `samples` configurations uniformly within the truth's joint limits (RandomConfigurations)
// and compares sensor and flange on them. Call CheckComparable first (abort on mismatch).
ModelComparison CompareModels(const RobotModel& truth, const RobotModel& model, std::size_t samples,
                              std::uint64_t seed);

// `model` with st(s_0), st(s_n) and every parameter outside model.mask taken from `truth`.
RobotModel WithUncalibratedFromTruth(const RobotModel& truth, const RobotModel& model);

// How far each link of the MCPC model (base, each segment, tool) moved from `before` to `after`:
// the rotation angle and the translation of its transform st(s_i). The models must have the same
// joint count. The acceptance gate bounds these per link (docs/daemon.md); the report shows them.
struct LinkChange {
  std::string link;  // "base", "A1->A2", ..., "A7->tool"
  double turn_rad = 0;
  double shift_m = 0;
};
std::vector<LinkChange> LinkChanges(const RobotModel& before, const RobotModel& after);

// Uniform random configurations within the joint limits of `model` (std::mt19937_64 seeded with
// `seed`): the same seed gives the same configurations.
std::vector<std::vector<double>> RandomConfigurations(const RobotModel& model, std::size_t count,
                                                      std::uint64_t seed);

}  // namespace selfcal
