#include "core/model/chain.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <numbers>

#include "core/model/kinematics.h"

namespace selfcal {
namespace {

// Axes closer to parallel than this (sine of the angle) are treated as parallel for the choice of
// Z_1; so are axes whose common normal is farther than kFarFoot from the joint frame, where the
// foot of the normal would be dominated by rounding (the DH discontinuity MCPC avoids elsewhere).
constexpr double kParallelSine = 1e-6;
constexpr double kFarFoot = 10.0;  // m
// |cos(beta)| below this: the segment is close to the MCPC singularity at beta = +-90 deg.
constexpr double kNearSingularCos = 1e-3;

std::string Format(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.6g", value);
  return buffer;
}

// Rounding leaves 1e-17 where a description had 0 and 1.5707963267948961 for pi/2. Snapping
// such values keeps model files readable; it moves no joint axis by more than kSnapAngle rad and
// no frame by more than kSnapLength m, far below the 1e-9 m the conversion promises.
constexpr double kSnapAngle = 1e-12;
constexpr double kSnapLength = 1e-13;

double SnapAngle(double angle) {
  const double quarter = std::numbers::pi / 2;
  const double k = std::round(angle / quarter);
  return std::abs(angle - k * quarter) < kSnapAngle ? (k == 0 ? 0.0 : k * quarter) : angle;
}
double SnapLength(double length) { return std::abs(length) < kSnapLength ? 0.0 : length; }

FullTransformParams Snap(FullTransformParams p) {
  p.alpha = SnapAngle(p.alpha);
  p.beta = SnapAngle(p.beta);
  p.gamma = SnapAngle(p.gamma);
  p.x = SnapLength(p.x);
  p.y = SnapLength(p.y);
  p.z = SnapLength(p.z);
  return p;
}

bool IsFinite(const Eigen::Isometry3d& T) { return T.matrix().allFinite(); }

// Any unit vector orthogonal to unit `z`, preferring `hint` projected.
Eigen::Vector3d OrthogonalUnit(const Eigen::Vector3d& z, const Eigen::Vector3d& hint) {
  Eigen::Vector3d v = hint - hint.dot(z) * z;
  if (v.norm() < 1e-9) {
    const Eigen::Vector3d other =
        std::abs(z.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    v = other - other.dot(z) * z;
  }
  return v.normalized();
}

Eigen::Isometry3d FrameOf(const Eigen::Vector3d& x, const Eigen::Vector3d& z,
                          const Eigen::Vector3d& origin) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = z.cross(x);
  T.linear().col(2) = z;
  T.translation() = origin;
  return T;
}

}  // namespace

Eigen::Isometry3d ChainForwardKinematics(const GenericChain& chain, std::span<const double> q) {
  const std::size_t n = chain.joints.size();
  if (q.size() != n || chain.fixed.size() != n + 1) {
    std::cerr << "selfcal: ChainForwardKinematics: " << q.size() << " positions, " << n
              << " joints, " << chain.fixed.size() << " fixed transforms\n";
    std::abort();
  }
  Eigen::Isometry3d T = chain.fixed[0];
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d axis = chain.joints[i].axis.normalized();
    Eigen::Isometry3d M = Eigen::Isometry3d::Identity();
    if (chain.joints[i].spec.type == JointType::kRevolute) {
      M.linear() = Eigen::AngleAxisd(q[i], axis).toRotationMatrix();
    } else {
      M.translation() = q[i] * axis;
    }
    T = T * M * chain.fixed[i + 1];
  }
  return T;
}

FullTransformParams ToFullTransformParams(const Eigen::Isometry3d& T) {
  const Eigen::Matrix3d& R = T.linear();
  FullTransformParams p;
  // Third column of rot_x(a) rot_y(b) rot_z(g) is (sin b, -sin a cos b, cos a cos b).
  p.alpha = std::hypot(R(1, 2), R(2, 2)) < 1e-12 ? 0.0 : std::atan2(-R(1, 2), R(2, 2));
  // Peel rot_x(alpha) off exactly, then read rot_y(b) rot_z(g):
  //   [[cb cg, -cb sg, sb], [sg, cg, 0], [-sb cg, sb sg, cb]].
  const Eigen::Matrix3d rest = Eigen::AngleAxisd(-p.alpha, Eigen::Vector3d::UnitX()) * R;
  p.gamma = std::atan2(rest(1, 0), rest(1, 1));
  p.beta = std::atan2(rest(0, 2), rest(2, 2));
  // st() translates after rotating: t = R (x, y, z).
  const Eigen::Vector3d local = R.transpose() * T.translation();
  p.x = local.x();
  p.y = local.y();
  p.z = local.z();
  return p;
}

Eigen::Isometry3d FromFullTransformParams(const FullTransformParams& p) {
  const double v[6] = {p.alpha, p.beta, p.gamma, p.x, p.y, p.z};
  return FullTransform<double>(v);
}

namespace {

// The chain at q = 0 in base coordinates: joint axis directions A_i, points P_i on them (the
// joint frames' origins), joint 1's frame and T_base_tip(0).
struct ChainAtZero {
  std::vector<Eigen::Vector3d> A, P;
  Eigen::Isometry3d first_joint_frame = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_base_tip = Eigen::Isometry3d::Identity();
};

// Empty when the chain has joints, n + 1 finite fixed transforms and usable axes.
std::string CheckChain(const GenericChain& chain) {
  const std::size_t n = chain.joints.size();
  if (n == 0) return "the chain has no joints";
  if (chain.fixed.size() != n + 1) {
    return "the chain has " + std::to_string(chain.fixed.size()) + " fixed transforms for " +
           std::to_string(n) + " joints (expected n + 1)";
  }
  for (std::size_t i = 0; i <= n; ++i) {
    if (!IsFinite(chain.fixed[i])) return "fixed transform " + std::to_string(i) + " is not finite";
  }
  for (const ChainJoint& joint : chain.joints) {
    if (!joint.axis.allFinite() || joint.axis.norm() < 1e-12) {
      return "joint " + joint.spec.name + ": the axis is zero or not finite";
    }
  }
  return {};
}

ChainAtZero ComposeAtZero(const GenericChain& chain) {
  const std::size_t n = chain.joints.size();
  ChainAtZero zero;
  zero.A.resize(n);
  zero.P.resize(n);
  zero.first_joint_frame = chain.fixed[0];
  Eigen::Isometry3d G = chain.fixed[0];
  for (std::size_t i = 0; i < n; ++i) {
    zero.A[i] = (G.linear() * chain.joints[i].axis.normalized()).normalized();
    zero.P[i] = G.translation();
    G = G * chain.fixed[i + 1];
  }
  zero.T_base_tip = G;
  return zero;
}

// Z_1: z on axis 1; x along a_1 x a_2 from the foot of the common normal, or (parallel or nearly
// parallel first axes, or a single joint) toward axis 2 from joint 1's origin.
Eigen::Isometry3d FirstMcpcFrame(const GenericChain& chain, const ChainAtZero& zero,
                                 std::vector<std::string>& notes) {
  const auto& A = zero.A;
  const auto& P = zero.P;
  const Eigen::Vector3d hint = zero.first_joint_frame.linear().col(0);
  if (chain.joints.size() < 2) return FrameOf(OrthogonalUnit(A[0], hint), A[0], P[0]);
  const Eigen::Vector3d normal = A[0].cross(A[1]);
  const double sine = normal.norm();
  if (sine >= kParallelSine) {
    // Foot of the common normal on axis 1: P_1 + t A_1.
    const Eigen::Vector3d w0 = P[0] - P[1];
    const double b = A[0].dot(A[1]);
    const double t = (b * A[1].dot(w0) - A[0].dot(w0)) / (1.0 - b * b);
    if (std::abs(t) <= kFarFoot) {
      // Either sign gives beta = y = 0; the one closer to the joint frame's x keeps the base
      // rotation small (identity for URDFs whose first joint frame is the base's).
      Eigen::Vector3d x1 = normal / sine;
      if (x1.dot(hint) < -1e-12) x1 = -x1;
      return FrameOf(x1, A[0], P[0] + t * A[0]);
    }
    notes.push_back("axes of " + chain.joints[0].spec.name + " and " + chain.joints[1].spec.name +
                    " are nearly parallel (common normal " + Format(t) +
                    " m away): treated as parallel, so the first segment's beta and y are not "
                    "zero");
  }
  const Eigen::Vector3d offset = P[1] - P[0];
  const Eigen::Vector3d perpendicular = offset - offset.dot(A[0]) * A[0];
  const Eigen::Vector3d x1 = perpendicular.norm() > 1e-12 ? OrthogonalUnit(A[0], perpendicular)
                                                          : OrthogonalUnit(A[0], hint);
  return FrameOf(x1, A[0], P[0]);
}

// st(s_i) from Z_i to Z_{i+1}: rotate about x and y onto axis i + 1 (unit `axis` through `point`,
// base coordinates), then shift along the new x and y onto it (revolute `next` joint only).
SegmentParams NextSegment(const Eigen::Isometry3d& Z, const Eigen::Vector3d& axis,
                          const Eigen::Vector3d& point, const JointSpec& joint,
                          const JointSpec& next, std::vector<std::string>& notes) {
  const Eigen::Vector3d w = Z.linear().transpose() * axis;
  SegmentParams s;
  s.beta = std::asin(std::clamp(w.x(), -1.0, 1.0));
  s.alpha = std::hypot(w.y(), w.z()) < 1e-12 ? 0.0 : std::atan2(-w.y(), w.z());
  if (std::abs(std::cos(s.beta)) < kNearSingularCos) {
    notes.push_back("segment " + joint.name + " -> " + next.name + ": beta = " + Format(s.beta) +
                    " rad, close to the MCPC singularity at +-90 deg");
  }
  // A prismatic axis has no position: nothing to shift.
  if (next.type == JointType::kRevolute) {
    const Eigen::Matrix3d R = Z.linear() * Eigen::AngleAxisd(s.alpha, Eigen::Vector3d::UnitX()) *
                              Eigen::AngleAxisd(s.beta, Eigen::Vector3d::UnitY());
    // The point of axis i + 1 whose offset from Z's origin is orthogonal to the axis.
    const Eigen::Vector3d& o = Z.translation();
    const Eigen::Vector3d z = R.col(2);
    const Eigen::Vector3d origin = point + (o - point).dot(z) * z;
    const Eigen::Vector3d local = R.transpose() * (origin - o);
    s.x = local.x();
    s.y = local.y();
  }
  s.alpha = SnapAngle(s.alpha);
  s.beta = SnapAngle(s.beta);
  s.x = SnapLength(s.x);
  s.y = SnapLength(s.y);
  return s;
}

}  // namespace

Expected<McpcConversion> ChainToMcpc(const GenericChain& chain) {
  if (std::string problem = CheckChain(chain); !problem.empty()) return Error{std::move(problem)};
  const std::size_t n = chain.joints.size();
  const ChainAtZero zero = ComposeAtZero(chain);
  McpcConversion result;
  RobotModel& model = result.model;
  model.name = chain.name;
  for (const ChainJoint& joint : chain.joints) model.joints.push_back(joint.spec);

  model.base = Snap(ToFullTransformParams(FirstMcpcFrame(chain, zero, result.notes)));
  // Every Z_i is recomposed from the stored parameters, so the model is exactly what FK composes.
  Eigen::Isometry3d Z = FromFullTransformParams(model.base);
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const SegmentParams s = NextSegment(Z, zero.A[i + 1], zero.P[i + 1], chain.joints[i].spec,
                                        chain.joints[i + 1].spec, result.notes);
    model.segments.push_back(s);
    const double v[4] = {s.alpha, s.beta, s.x, s.y};
    Z = Z * SegmentTransform<double>(v);
  }
  model.tool = Snap(ToFullTransformParams(Z.inverse() * zero.T_base_tip));
  model.mask = DefaultMask(model);
  return result;
}

GenericChain McpcToChain(const RobotModel& model) {
  GenericChain chain;
  chain.name = model.name;
  chain.fixed.push_back(FromFullTransformParams(model.base));
  for (std::size_t i = 0; i < model.JointCount(); ++i) {
    chain.joints.push_back({model.joints[i], Eigen::Vector3d::UnitZ()});
    if (i + 1 < model.JointCount()) {
      const SegmentParams& s = model.segments[i];
      const double v[4] = {s.alpha, s.beta, s.x, s.y};
      chain.fixed.push_back(SegmentTransform<double>(v));
    }
  }
  chain.fixed.push_back(FromFullTransformParams(model.tool));
  return chain;
}

GenericChain DhToChain(const DhTable& table) {
  GenericChain chain;
  chain.name = table.name;
  chain.fixed.push_back(table.T_base_frame0);
  for (std::size_t i = 0; i < table.rows.size(); ++i) {
    const DhRow& row = table.rows[i];
    chain.joints.push_back({row.joint, Eigen::Vector3d::UnitZ()});
    // rot_z(q) and trans_z(q) commute with rot_z(theta) trans_z(d): the joint motion can go first.
    Eigen::Isometry3d F = Eigen::Isometry3d::Identity();
    F.rotate(Eigen::AngleAxisd(row.theta, Eigen::Vector3d::UnitZ()));
    F.translate(Eigen::Vector3d(0, 0, row.d));
    F.translate(Eigen::Vector3d(row.a, 0, 0));
    F.rotate(Eigen::AngleAxisd(row.alpha, Eigen::Vector3d::UnitX()));
    if (i + 1 == table.rows.size()) F = F * table.T_framen_tool;
    chain.fixed.push_back(F);
  }
  if (table.rows.empty()) chain.fixed.push_back(table.T_framen_tool);
  return chain;
}

}  // namespace selfcal
