#include "core/calib/pose_jacobian.h"

namespace selfcal::calib {

namespace {

// Accumulates the chain factor by factor. Each parameter enters through one elementary factor
// E(theta) (a rotation about or a translation along a local axis u), so with A = prefix * E:
//   dT/dtheta = A G A^-1 T, G the local generator; in the base frame that is the twist
//   rotation:    omega = R_A u, v = t_A x omega
//   translation: omega = 0,     v = R_A u.
class ChainWalker {
 public:
  ChainWalker(PoseJacobian& jacobian) : jacobian_(jacobian) { accumulated_.setIdentity(); }

  void Rotate(int axis, double angle, long column) {
    Eigen::Vector3d u = Eigen::Vector3d::Zero();
    u[axis] = 1.0;
    accumulated_ = accumulated_ * Transform3<double>(Eigen::AngleAxisd(angle, u));
    if (column >= 0) {
      const Eigen::Vector3d omega = accumulated_.linear() * u;
      jacobian_.col(column).head<3>() = accumulated_.translation().cross(omega);
      jacobian_.col(column).tail<3>() = omega;
    }
  }
  void Translate(int axis, double distance, long column) {
    Eigen::Vector3d u = Eigen::Vector3d::Zero();
    u[axis] = 1.0;
    const Eigen::Vector3d direction = accumulated_.linear() * u;
    if (column >= 0) {
      jacobian_.col(column).head<3>() = direction;
      jacobian_.col(column).tail<3>().setZero();
    }
    accumulated_.translation() += direction * distance;
  }
  // st() with six parameters: rot_x rot_y rot_z trans(x, y, z) (translations commute).
  void Full(const double* p, long first_column) {
    Rotate(0, p[0], first_column + 0);
    Rotate(1, p[1], first_column + 1);
    Rotate(2, p[2], first_column + 2);
    Translate(0, p[3], first_column + 3);
    Translate(1, p[4], first_column + 4);
    Translate(2, p[5], first_column + 5);
  }
  // st() between joints: rot_x rot_y trans(x, y, 0).
  void Segment(const double* p, long first_column) {
    Rotate(0, p[0], first_column + 0);
    Rotate(1, p[1], first_column + 1);
    Translate(0, p[2], first_column + 2);
    Translate(1, p[3], first_column + 3);
  }
  void Joint(JointType type, double position) {
    if (type == JointType::kRevolute) {
      Rotate(2, position, -1);
    } else {
      Translate(2, position, -1);
    }
  }
  const Transform3<double>& accumulated() const { return accumulated_; }

 private:
  PoseJacobian& jacobian_;
  Transform3<double> accumulated_;
};

}  // namespace

void ForwardKinematicsWithJacobian(std::span<const JointType> joint_types, const double* parameters,
                                   const double* joint_positions, Transform3<double>& T_base_sensor,
                                   PoseJacobian& jacobian) {
  const std::size_t n = joint_types.size();
  const long parameter_count =
      static_cast<long>(2 * kFullTransformParamCount + kSegmentParamCount * (n - 1));
  jacobian.resize(6, parameter_count);
  ChainWalker walker(jacobian);
  walker.Full(parameters + kBaseOffset, static_cast<long>(kBaseOffset));
  for (std::size_t i = 0; i < n; ++i) {
    walker.Joint(joint_types[i], joint_positions[i]);
    if (i + 1 < n)
      walker.Segment(parameters + SegmentOffset(i), static_cast<long>(SegmentOffset(i)));
  }
  walker.Full(parameters + ToolOffset(n), static_cast<long>(ToolOffset(n)));
  T_base_sensor = walker.accumulated();
}

}  // namespace selfcal::calib
