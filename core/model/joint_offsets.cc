#include "core/model/joint_offsets.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "core/model/chain.h"
#include "core/model/evaluation.h"
#include "core/model/kinematics.h"

namespace selfcal {
namespace {

// Position [m] and rotation vector [rad] of `to` relative to `from`, stacked.
Eigen::Matrix<double, 6, 1> PoseDifference(const Transform3<double>& from,
                                           const Transform3<double>& to) {
  Eigen::Matrix<double, 6, 1> difference;
  difference.head<3>() = to.translation() - from.translation();
  const Eigen::AngleAxisd rotation(from.linear().transpose() * to.linear());
  difference.tail<3>() = rotation.angle() * rotation.axis();
  return difference;
}

// The mount change of the unknowns x (offsets of joints 1..n-1, then the mount's translation and
// rotation vector), from position `at`.
Transform3<double> Mount(const Eigen::VectorXd& x, Eigen::Index at) {
  const Eigen::Vector3d t = x.segment<3>(at), w = x.segment<3>(at + 3);
  Transform3<double> mount = Transform3<double>::Identity();
  mount.translation() = t;
  if (w.norm() > 0) mount.linear() = Eigen::AngleAxisd(w.norm(), w.normalized()).matrix();
  return mount;
}

struct Problem {
  const RobotModel& nominal;
  std::vector<std::vector<double>> q;
  std::vector<Transform3<double>> targets;  // the calibrated model's sensor poses

  std::size_t FreeOffsets() const { return nominal.JointCount() - 1; }

  // Stacked differences of nominal(q + offsets) * mount against the targets, 6 per sample.
  Eigen::VectorXd Residuals(const Eigen::VectorXd& x) const {
    const std::size_t n = nominal.JointCount();
    const Transform3<double> mount = Mount(x, static_cast<Eigen::Index>(FreeOffsets()));
    Eigen::VectorXd r(static_cast<Eigen::Index>(6 * q.size()));
    std::vector<double> shifted(n);
    for (std::size_t s = 0; s < q.size(); ++s) {
      for (std::size_t i = 0; i < n; ++i) {
        shifted[i] = q[s][i] + (i < FreeOffsets() ? x[static_cast<Eigen::Index>(i)] : 0.0);
      }
      r.segment<6>(static_cast<Eigen::Index>(6 * s)) =
          PoseDifference(targets[s], ForwardKinematics(nominal, shifted) * mount);
    }
    return r;
  }
};

}  // namespace

JointOffsetFit FitJointOffsets(const RobotModel& nominal, const RobotModel& calibrated,
                               std::size_t samples, std::uint64_t seed) {
  if (!CheckComparable(nominal, calibrated).empty()) std::abort();
  Problem problem{nominal, RandomConfigurations(nominal, samples, seed), {}};
  for (const auto& q : problem.q) problem.targets.push_back(ForwardKinematics(calibrated, q));

  const auto unknowns = static_cast<Eigen::Index>(problem.FreeOffsets() + 6);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(unknowns);
  constexpr double kStep = 1e-7;  // central differences: the kinematics are smooth
  for (int iteration = 0; iteration < 20; ++iteration) {
    const Eigen::VectorXd r = problem.Residuals(x);
    Eigen::MatrixXd jacobian(r.size(), unknowns);
    for (Eigen::Index i = 0; i < unknowns; ++i) {
      Eigen::VectorXd plus = x, minus = x;
      plus[i] += kStep;
      minus[i] -= kStep;
      jacobian.col(i) = (problem.Residuals(plus) - problem.Residuals(minus)) / (2 * kStep);
    }
    const Eigen::VectorXd step = jacobian.colPivHouseholderQr().solve(-r);
    x += step;
    if (step.norm() < 1e-11) break;  // rad or m: far below any offset that matters
  }

  JointOffsetFit fit;
  fit.offsets.assign(nominal.JointCount(), 0.0);
  for (std::size_t i = 0; i < problem.FreeOffsets(); ++i) {
    fit.offsets[i] = x[static_cast<Eigen::Index>(i)];
  }
  const auto mount_at = static_cast<Eigen::Index>(problem.FreeOffsets());
  fit.mount_shift = x.segment<3>(mount_at);
  fit.mount_turn = x.segment<3>(mount_at + 3);
  fit.mount_shift_m = fit.mount_shift.norm();
  fit.mount_turn_rad = fit.mount_turn.norm();
  fit.samples = problem.q.size();
  const Eigen::VectorXd r = problem.Residuals(x);
  double position = 0, orientation = 0;
  for (std::size_t s = 0; s < problem.q.size(); ++s) {
    position += r.segment<3>(static_cast<Eigen::Index>(6 * s)).squaredNorm();
    orientation += r.segment<3>(static_cast<Eigen::Index>(6 * s + 3)).squaredNorm();
  }
  const double count = static_cast<double>(std::max<std::size_t>(problem.q.size(), 1));
  fit.rms_position_m = std::sqrt(position / count);
  fit.rms_orientation_rad = std::sqrt(orientation / count);
  return fit;
}

Expected<RobotModel> WithJointOffsets(const RobotModel& model, const std::vector<double>& offsets) {
  if (offsets.size() != model.JointCount()) {
    return Error{"joint offsets: " + std::to_string(offsets.size()) + " values for " +
                 std::to_string(model.JointCount()) + " joints"};
  }
  GenericChain chain = McpcToChain(model);
  for (std::size_t i = 0; i < offsets.size(); ++i) {
    // F_{i} precedes joint i + 1 (0-based i): a zero offset is a turn (shift) about its axis z.
    if (model.joints[i].type == JointType::kRevolute) {
      chain.fixed[i] = chain.fixed[i] * Eigen::AngleAxisd(offsets[i], Eigen::Vector3d::UnitZ());
    } else {
      chain.fixed[i] = chain.fixed[i] * Eigen::Translation3d(0, 0, offsets[i]);
    }
  }
  auto converted = ChainToMcpc(chain);
  if (!converted) return converted.error();
  converted->model.name = model.name;
  converted->model.mask = model.mask;
  return std::move(converted->model);
}

Expected<std::vector<bool>> RemasterMask(const RobotModel& model) {
  if (const std::string problem = CheckConsistency(model); !problem.empty()) {
    return Error{"remaster: " + problem};
  }
  const std::size_t n = model.JointCount();
  std::vector<bool> mask(model.ParameterCount(), false);
  constexpr double kStep = 1e-6;  // rad or m; central differences through the conversion
  for (std::size_t joint = 0; joint + 1 < n; ++joint) {
    std::vector<double> plus(n, 0.0), minus(n, 0.0);
    plus[joint] = kStep;
    minus[joint] = -kStep;
    const auto model_plus = WithJointOffsets(model, plus);
    if (!model_plus) return model_plus.error();
    const auto model_minus = WithJointOffsets(model, minus);
    if (!model_minus) return model_minus.error();
    const std::vector<double> k_plus = ToParameterVector(*model_plus);
    const std::vector<double> k_minus = ToParameterVector(*model_minus);
    for (std::size_t i = 0; i < mask.size(); ++i) {
      if (std::abs(k_plus[i] - k_minus[i]) / (2 * kStep) >= kRemasterSensitivity) mask[i] = true;
    }
  }
  for (std::size_t i = ToolOffset(n); i < mask.size(); ++i) mask[i] = true;
  for (std::size_t i = 0; i < mask.size(); ++i) mask[i] = mask[i] && model.mask[i];
  return mask;
}

}  // namespace selfcal
