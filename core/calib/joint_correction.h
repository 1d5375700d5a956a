// Engine parameters beyond MCPC that act in joint space (docs/engine.md, deviations 15, 16):
//   q_eff = q(theta_hat),   G = d q_eff / d theta_hat,
// with theta_hat appended to the normalized MCPC parameters k_hat (column c of G is flat
// parameter K + c). The pose's derivative by theta_hat_c is
// the joints' Jacobian (their twists, core/model/jacobian.h) times G_c, so the fast solver, the
// rigid-pair reduction and the moving matches through knots take the extra columns like any
// parameter. This is the one home of the joint-space parameters beyond MCPC: the elasticity's
// columns first, then the latency's; a later kind appends its own columns here and its naming
// and units to calibrate.cc's DescribeFree. (The sensor's intrinsics move no joint: they follow
// these in k_hat, sensor_intrinsics.h.)
//
// Joint elasticity fills it: column c acts on joint joints[c] alone,
//   G_{joints[c], c}(q) = tau_j(q) / reference_torque[c],
// tau the gravity torque of core/model/gravity.h at `frozen_parameters` (the estimate at the
// start of the ICP iteration, held fixed during one Levenberg-Marquardt solve as the normals
// are). So theta_hat_c = compliance * reference_torque[c] is the joint's deflection in rad at the
// largest gravity torque the fit scans give it: O(1e-3) for a stiff arm, and a step of the
// epsilon stop criterion compares rad with rad like the angles of k_hat.
//
// The sensor latency (deviation 16) follows: one column per recording, theta_hat its latency
// in s. A pose of that recording takes the joints interpolated at its measurement time +
// theta_hat from the recording's joint states (Dataset::pose_utime, joint_states; JointsAt),
// not its recorded joints (interpolated at the start value, Dataset::joint_latency_s, the same
// numbers there), and G = qdot, the joint velocity at that time (JointVelocitiesAt): exact at
// every latency, no expansion about the start. 0 for the other recordings' poses and for poses
// without joint timing. A scan taken at rest has qdot ~ 0: its latency is not observable
// (calibrate.cc keeps the start value and names it).
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "core/calib/dataset.h"
#include "core/model/robot_model.h"

namespace selfcal::calib {

inline constexpr std::size_t kMaxCorrectionColumns = 32;
// rad/s: a recording none of whose fit scans moves its joints faster than this (RMS over the
// scan's poses) was taken at rest; its latency is not estimated (calibrate.cc). Far above the
// velocity noise of JointVelocitiesAt (encoder noise 2e-5 rad: 3e-3 rad/s), far below any scan
// motion (line sweeps about 1 rad/s, LiDAR sweeps 0.35 rad/s).
inline constexpr double kMinLatencySpeed = 0.01;

struct JointCorrection {
  // Joint elasticity: columns 0 .. joints.size() - 1.
  std::vector<std::size_t> joints;        // the joint each column acts on
  std::vector<double> reference_torque;   // Nm per column (theta_hat = compliance * this)
  GravityLoad load;                       // the masses of the gravity torque
  std::vector<double> frozen_parameters;  // flat MCPC parameters (SI) where tau is evaluated
  // Sensor latency: then one column per entry, the recording it belongs to (PoseState) and the
  // latency [s] that recording's joints were interpolated at (its start value).
  std::vector<int> latency_recordings;
  std::vector<double> latency_start_s;
  // Without calibrated elasticity: the robot model's compliance per joint [rad/Nm] (empty =
  // none), applied with the same gravity torque but no column. A compliance the calibration does
  // not free keeps the model's value, as a masked MCPC parameter does; fitting a rigid arm
  // instead would move the zero offsets and lengths to absorb the sag the model already knows.
  std::vector<double> held_compliance;

  std::size_t ElasticityCount() const { return joints.size(); }
  std::size_t Count() const { return joints.size() + latency_recordings.size(); }
  // True when q_eff is the raw q: no column and nothing held.
  bool Empty() const { return Count() == 0 && held_compliance.empty(); }

  // q_eff for the raw joint state `state` (n joints) into `q_eff`; when `G` is not null, it
  // receives G, n x Count() column-major (column c at G + c n).
  void Apply(std::span<const JointType> joint_types, const PoseState& state,
             const double* theta_hat, double* q_eff, double* G) const;
  // The latency column that acts on `state`, or -1.
  long LatencyColumnOf(const PoseState& state) const;
};

// Joint elasticity for `model` (its gravity load) over the poses `configurations` (n joint
// positions each, raw units): the revolute joints whose largest gravity torque over them, at the
// model's parameters, reaches kMinTorqueShare of the largest joint's (A1 of an upright arm has
// none: its compliance would be unobservable), with that torque as their reference.
inline constexpr double kMinTorqueShare = 0.005;
JointCorrection ElasticityCorrection(const RobotModel& model,
                                     const std::vector<const double*>& configurations);

// The least value of each free parameter (`free`: indices into k_hat, the correction's columns
// from `first_column` on): 0 for a joint's compliance, -infinity for every other. A compliance
// below 0 would be a joint that rises against gravity; left free, one took up what the wrist's
// others could not tell apart (docs/engine.md, deviation 15).
std::vector<double> LowerBounds(const JointCorrection& correction, std::size_t first_column,
                                const std::vector<std::size_t>& free);

// True when `model` has a non-zero compliance (a calibration's with elasticity).
bool HasCompliance(const RobotModel& model);
// The model's compliance held, not calibrated (held_compliance); `model` must have its gravity
// load (RobotModel::gravity).
JointCorrection HeldCompliance(const RobotModel& model);

// Adds a latency column to `correction` for every recording of `datasets` whose fit scans carry
// joint timing (Dataset::HasJointTiming), in the order the datasets name them, starting at their
// joint_latency_s. Returns the columns added.
std::size_t AddLatencyColumns(const std::vector<Dataset>& datasets, JointCorrection& correction);

}  // namespace selfcal::calib
