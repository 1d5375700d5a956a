#include "core/sim/ik.h"

#include <algorithm>

#include "core/model/kinematics.h"

namespace selfcal::sim {

Eigen::Vector3d RotationError(const Eigen::Matrix3d& R_goal, const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd error(R_goal * R.transpose());
  return error.axis() * error.angle();
}

std::vector<double> RandomConfiguration(const RobotModel& model, double margin, Random& random) {
  std::vector<double> q(model.JointCount());
  for (std::size_t j = 0; j < q.size(); ++j) {
    q[j] = random.Uniform(model.joints[j].lower + margin, model.joints[j].upper - margin);
  }
  return q;
}

std::optional<std::vector<double>> SolveIk(const RobotModel& model,
                                           const Eigen::Isometry3d& T_base_sensor,
                                           const std::vector<double>& seed, Random& random,
                                           const IkOptions& options) {
  const std::size_t n = model.JointCount();
  const double step = 1e-6;
  for (int attempt = 0; attempt < options.restarts; ++attempt) {
    std::vector<double> q = (attempt == 0 && seed.size() == n)
                                ? seed
                                : RandomConfiguration(model, options.limit_margin, random);
    for (int iteration = 0; iteration < options.iterations; ++iteration) {
      const Eigen::Isometry3d T = ForwardKinematics(model, q);
      Eigen::Matrix<double, 6, 1> error;
      error.head<3>() = T_base_sensor.translation() - T.translation();
      error.tail<3>() = RotationError(T_base_sensor.linear(), T.linear());
      if (error.head<3>().norm() < options.position_tolerance &&
          error.tail<3>().norm() < options.angle_tolerance) {
        return q;
      }
      Eigen::MatrixXd J(6, n);
      for (std::size_t j = 0; j < n; ++j) {
        std::vector<double> moved = q;
        moved[j] += step;
        const Eigen::Isometry3d Tj = ForwardKinematics(model, moved);
        J.block<3, 1>(0, static_cast<Eigen::Index>(j)) =
            (Tj.translation() - T.translation()) / step;
        J.block<3, 1>(3, static_cast<Eigen::Index>(j)) =
            RotationError(Tj.linear(), T.linear()) / step;
      }
      const double damping = 1e-2;
      const Eigen::Matrix<double, 6, 6> JJt =
          J * J.transpose() + damping * damping * Eigen::Matrix<double, 6, 6>::Identity();
      Eigen::VectorXd dq = J.transpose() * JJt.ldlt().solve(error);
      const double norm = dq.norm();
      if (norm > 0.3) dq *= 0.3 / norm;
      for (std::size_t j = 0; j < n; ++j) {
        q[j] = std::clamp(q[j] + dq[static_cast<Eigen::Index>(j)],
                          model.joints[j].lower + options.limit_margin,
                          model.joints[j].upper - options.limit_margin);
      }
    }
  }
  return std::nullopt;
}

}  // namespace selfcal::sim
