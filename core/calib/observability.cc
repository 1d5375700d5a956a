#include "core/calib/observability.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>

namespace selfcal::calib {

Observability AnalyzeObservability(const Eigen::MatrixXd& hessian, double residual_sum_squares,
                                   std::size_t residuals, const std::vector<std::string>& names,
                                   double correlation_limit) {
  Observability result;
  const long K = hessian.rows();
  result.std_dev.assign(static_cast<std::size_t>(K), std::numeric_limits<double>::infinity());
  if (K == 0) return result;
  const double dof = static_cast<double>(residuals) - static_cast<double>(K);
  const double sigma2 = dof > 0 ? residual_sum_squares / dof : 0.0;
  // Scale to unit diagonal so that the rank test does not depend on units.
  Eigen::VectorXd d = hessian.diagonal().cwiseMax(0.0).cwiseSqrt();
  std::vector<bool> unobserved(static_cast<std::size_t>(K), false);
  Eigen::VectorXd inverse_d(K);
  for (long i = 0; i < K; ++i) {
    unobserved[static_cast<std::size_t>(i)] = !(d[i] > 0);
    inverse_d[i] = d[i] > 0 ? 1.0 / d[i] : 0.0;
    if (unobserved[static_cast<std::size_t>(i)]) {
      result.poorly_observable.push_back(names[static_cast<std::size_t>(i)] +
                                         ": not observed (zero derivative)");
    }
  }
  const Eigen::MatrixXd scaled = inverse_d.asDiagonal() * hessian * inverse_d.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(scaled);
  const Eigen::VectorXd values = eigen.eigenvalues();
  const double largest = values.maxCoeff();
  const double threshold = largest * 1e-10;
  // Pseudo-inverse in the scaled space; null directions name their main parameters.
  Eigen::MatrixXd scaled_inverse = Eigen::MatrixXd::Zero(K, K);
  for (long e = 0; e < K; ++e) {
    const Eigen::VectorXd v = eigen.eigenvectors().col(e);
    if (values[e] > threshold) {
      scaled_inverse += v * v.transpose() / values[e];
      continue;
    }
    std::string involved;
    for (long i = 0; i < K; ++i) {
      if (std::abs(v[i]) > 0.3 && !unobserved[static_cast<std::size_t>(i)]) {
        involved += (involved.empty() ? "" : ", ") + names[static_cast<std::size_t>(i)];
      }
    }
    if (!involved.empty()) {
      result.poorly_observable.push_back(
          involved + ": rank deficient together (a combination is not observable)");
    }
  }
  for (long i = 0; i < K; ++i) {
    if (unobserved[static_cast<std::size_t>(i)]) continue;
    result.std_dev[static_cast<std::size_t>(i)] =
        std::sqrt(sigma2 * scaled_inverse(i, i)) * inverse_d[i];
  }
  for (long a = 0; a < K; ++a) {
    for (long b = a + 1; b < K; ++b) {
      const double denominator = std::sqrt(scaled_inverse(a, a) * scaled_inverse(b, b));
      if (!(denominator > 0)) continue;
      const double correlation = scaled_inverse(a, b) / denominator;
      if (std::abs(correlation) > correlation_limit) {
        char text[64];
        std::snprintf(text, sizeof(text), "%.3f", correlation);
        result.poorly_observable.push_back(names[static_cast<std::size_t>(a)] + ", " +
                                           names[static_cast<std::size_t>(b)] + ": correlation " +
                                           text);
      }
    }
  }
  return result;
}

}  // namespace selfcal::calib
