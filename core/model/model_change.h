// What changed between the installed model and a new calibration of the same arm, in the words of
// the technician who triggered it: a joint that lost its zero (a motor or gearbox swap, a lost
// mastering), a sensor mount that moved (a bump), link geometry that changed (a collision), or no
// significant change. Built on the joint offset fit (joint_offsets.h): the offsets and the mount
// change that best explain the new model from the installed one, and what they leave unexplained.
//
// A change counts when it exceeds both a floor (what matters on a robot cell) and `sigmas`
// standard deviations of what the calibration's own uncertainty would show with nothing changed:
// the fit repeated on draws of the calibrated parameters from the result's covariance, against the
// calibrated model itself (a null distribution; without a covariance only the floors apply).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/model/evaluation.h"
#include "core/model/joint_offsets.h"
#include "core/model/robot_model.h"
#include "core/util/enum_names.h"

namespace selfcal {

struct ChangeThresholds {
  double joint_offset_rad = 1.745329e-4;  // 0.01 deg
  double mount_shift_m = 0.5e-3;
  double mount_turn_rad = 8.72665e-4;  // 0.05 deg
  double geometry_m = 0.3e-3;          // sensor RMS the offsets and the mount leave unexplained
  double sigmas = 3;
  int draws = 32;  // of the null distribution
  std::uint64_t seed = 1;
};

enum class ChangeKind { kJointZero, kSensorMount, kLinkGeometry };
// The kinds' names, as the result file's change: findings write them and the report reads them.
inline constexpr EnumNames<ChangeKind, 3> kChangeKindNames{{
    {ChangeKind::kJointZero, "joint_zero"},
    {ChangeKind::kSensorMount, "sensor_mount"},
    {ChangeKind::kLinkGeometry, "link_geometry"},
}};
const char* ChangeKindName(ChangeKind kind);  // "joint_zero", "sensor_mount", "link_geometry"

struct ChangeFinding {
  ChangeKind kind = ChangeKind::kJointZero;
  std::string joint;    // kJointZero: the joint's name
  double value = 0;     // rad (joint zero), m (mount shift, unexplained sensor RMS)
  double turn_rad = 0;  // kSensorMount: the mount's rotation
  // Of `value` and `turn_rad` in the null distribution; 0 = no covariance given.
  double std_dev = 0, turn_std_dev_rad = 0;
  std::string text;  // "joint A4 zero offset moved 0.41 deg (mastering lost?)"
};

struct ModelChange {
  JointOffsetFit fit;                   // installed -> calibrated
  std::vector<ChangeFinding> findings;  // empty = no significant change
  // Had the installed model been kept: its error against the new one (taken as the truth), at
  // the sensor and at the flange (CompareModels), over the fit's configurations count.
  ModelComparison kept_installed;
  // The findings' texts joined by "; " (links, mount, then joints; three or more moved zeros as one
  // phrase), or "no significant change".
  std::string Summary() const;
};

// `covariance` (SI) over the flat parameter indices `free`, as CalibrationResult::covariance (an
// index beyond the model's parameters, of a parameter that is not kinematic, is left out); an
// empty matrix = floors only. The models must be comparable (CheckComparable; abort if not).
ModelChange DescribeModelChange(const RobotModel& installed, const RobotModel& calibrated,
                                const Eigen::MatrixXd& covariance,
                                const std::vector<std::size_t>& free,
                                const ChangeThresholds& thresholds = {});

}  // namespace selfcal
