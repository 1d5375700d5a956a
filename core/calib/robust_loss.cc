#include "core/calib/robust_loss.h"

#include <cmath>

namespace selfcal::calib {

RobustLoss MakeRobustLoss(const CalibrationOptions& options, double scale) {
  RobustLoss loss;
  loss.kind = options.loss;
  loss.width = options.loss_width;
  loss.sigma_abs = options.sigma_abs / scale;
  loss.sigma_rel = options.sigma_rel;
  return loss;
}

std::vector<float> MatchWeights(const RobustLoss& loss, CostKind cost, const PairMatches& matches,
                                const ProjectedCloud& cloud_i, const ProjectedCloud& cloud_j,
                                const Dataset& dataset_i, const Dataset& dataset_j, double scale) {
  std::vector<float> weights;
  if (!loss.Active()) return weights;
  weights.resize(matches.size());
  const double inverse_scale = 1.0 / scale;
  auto sigma = [&](const Dataset& dataset, std::uint32_t point) {
    const double range = std::sqrt(double{dataset.x[point]} * dataset.x[point] +
                                   double{dataset.y[point]} * dataset.y[point] +
                                   double{dataset.z[point]} * dataset.z[point]) *
                         inverse_scale;
    return loss.sigma_abs + loss.sigma_rel * range;
  };
  for (std::size_t k = 0; k < matches.size(); ++k) {
    const std::uint32_t u = matches.point_i[k], v = matches.point_j[k];
    const Eigen::Vector3f n = MatchNormal(cost, cloud_i, u, cloud_j, v);
    const double residual = static_cast<double>(n.dot(cloud_i.Point(u) - cloud_j.Point(v)));
    const double sigma_i = sigma(dataset_i, u), sigma_j = sigma(dataset_j, v);
    const double kernel = loss.width * std::sqrt(sigma_i * sigma_i + sigma_j * sigma_j);
    weights[k] = static_cast<float>(CauchyWeight(residual, kernel));
  }
  return weights;
}

}  // namespace selfcal::calib
