// Standard deviations and poorly observable parameters from the normal matrix J^T J at the
// solution (Gauss-Newton covariance sigma^2 (J^T J)^-1, sigma^2 = sum r^2 / (N - K)), the same
// quantity ceres::Covariance computes. DELIBERATE DEVIATION from "Ceres covariance": we build
// J^T J with our per-pose Jacobians (point_to_plane.h) in both solver modes, so memory stays
// O(K^2) instead of a dense N x K Jacobian.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace selfcal::calib {

struct Observability {
  std::vector<double> std_dev;                 // per free parameter, normalized units
  std::vector<std::string> poorly_observable;  // "name: reason"
};

// `names` has one name per free parameter; `residual_sum_squares` = sum r^2, `residuals` = N.
Observability AnalyzeObservability(const Eigen::MatrixXd& hessian, double residual_sum_squares,
                                   std::size_t residuals, const std::vector<std::string>& names,
                                   double correlation_limit = 0.95);

}  // namespace selfcal::calib
