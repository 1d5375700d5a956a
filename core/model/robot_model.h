// The MCPC kinematic model of DESIGN.md and the paper's "Fundamentals" section.
//
// tr(k, j) = st(s_0) * jt(j_1) * st(s_1) * ... * jt(j_n) * st(s_n)
//
// The parameter vector k is stored flat, base to tip:
//   base    st(s_0):  alpha, beta, gamma, x, y, z         (6, never calibrated)
//   segment st(s_i):  alpha, beta, x, y                    (4 each, i = 1..n-1)
//   tool    st(s_n):  alpha, beta, gamma, x, y, z          (6, last joint to sensor)
// Angles in rad, translations in m.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace selfcal {

enum class JointType { kRevolute, kPrismatic };

struct JointSpec {
  std::string name;
  JointType type = JointType::kRevolute;
  double lower = 0.0;             // rad or m
  double upper = 0.0;             // rad or m
  double max_velocity = 0.0;      // rad/s or m/s
  double max_acceleration = 0.0;  // rad/s^2 or m/s^2
};

// st() with all six degrees of freedom: rot_x(alpha) * rot_y(beta) * rot_z(gamma) * trans(x, y, z).
struct FullTransformParams {
  double alpha = 0, beta = 0, gamma = 0, x = 0, y = 0, z = 0;
};

// st() between two joints: rot_x(alpha) * rot_y(beta) * trans(x, y, 0).
struct SegmentParams {
  double alpha = 0, beta = 0, x = 0, y = 0;
};

inline constexpr std::size_t kFullTransformParamCount = 6;
inline constexpr std::size_t kSegmentParamCount = 4;

// K = 12 + 4 (n - 1): the flat parameter count of a chain with n >= 1 joints.
inline constexpr std::size_t ParameterCountOf(std::size_t joint_count) {
  return 2 * kFullTransformParamCount + kSegmentParamCount * (joint_count - 1);
}

// The arm's gravity load for joint elasticity (core/model/gravity.h; the model file's optional
// `gravity:` block, docs/formats.md). Empty link_masses = not given.
struct GravityLoad {
  std::vector<double> link_masses;  // kg per joint's link (the body joint i turns), base to tip
  double sensor_mass = 0;           // kg at the tool point (the sensor's origin)
  // rad/Nm per joint, 1 sigma: how far a rigid model's compliance may be from the arm's, which
  // the covariance includes where elasticity is not calibrated (docs/engine.md, deviation 21);
  // empty = not given.
  std::vector<double> compliance_sd;
  bool Present() const { return !link_masses.empty(); }
};

struct RobotModel {
  std::string name;
  std::vector<JointSpec> joints;        // n joints, base to tip
  FullTransformParams base;             // st(s_0)
  std::vector<SegmentParams> segments;  // st(s_1) .. st(s_{n-1}): n - 1 entries
  FullTransformParams tool;             // st(s_n)
  std::vector<bool> mask;               // one flag per flat parameter: true = calibrated
  GravityLoad gravity;                  // optional: masses for joint elasticity
  // Optional: rad/Nm per joint, q_real = q + compliance_j * tau_j(q) (gravity.h); empty = a rigid
  // arm. A calibration with elasticity writes it (docs/engine.md, deviation 15). Forward
  // kinematics of RobotModel (kinematics.h, evaluation.h) is that of the rigid arm.
  std::vector<double> compliance;
  // Optional: the links' radius [m] as capsules along the kinematics (arm_capsules.h); 0 = not
  // given. The engine removes the points it sees on its own links (docs/engine.md, deviation 20).
  double link_radius = 0;
  static constexpr double kMaxLinkRadius = 0.5;  // m: beyond, a mistake (CheckConsistency says so)

  std::size_t JointCount() const { return joints.size(); }
  std::size_t ParameterCount() const {
    return 2 * kFullTransformParamCount + kSegmentParamCount * segments.size();
  }
};

// Offsets into the flat parameter vector.
inline constexpr std::size_t kBaseOffset = 0;
inline std::size_t SegmentOffset(std::size_t segment_index) {
  return kFullTransformParamCount + kSegmentParamCount * segment_index;
}
inline std::size_t ToolOffset(std::size_t joint_count) {
  return kFullTransformParamCount + kSegmentParamCount * (joint_count - 1);
}

// The flat parameter vector of `model` (layout above) and back.
std::vector<double> ToParameterVector(const RobotModel& model);
void FromParameterVector(const std::vector<double>& parameters, RobotModel& model);

// Human-readable name of flat parameter `index`, e.g. "A2->A3.beta", "base.z", "A7->tool.gamma".
std::string ParameterName(const RobotModel& model, std::size_t index);

// True for the translation parameters (x, y, z of st(s_0) and st(s_n), x and y of the segments),
// which the engine normalizes by s; the second form for callers that have only the joint count.
bool IsTranslationParameter(const RobotModel& model, std::size_t index);
bool IsTranslationIndex(std::size_t index, std::size_t joint_count);

// The paper's default mask: base never; first segment alpha and x (beta and y are not
// observable); other segments all four (prismatic: alpha and beta only); tool all six.
std::vector<bool> DefaultMask(const RobotModel& model);

// Checks sizes: n >= 1 joints, n - 1 segments, a mask of ParameterCount() entries, limits ordered.
// Returns an empty string when consistent, otherwise what is wrong.
std::string CheckConsistency(const RobotModel& model);

}  // namespace selfcal
