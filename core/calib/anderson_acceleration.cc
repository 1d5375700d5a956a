#include "core/calib/anderson_acceleration.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <utility>

namespace selfcal::calib {

AndersonAcceleration::AndersonAcceleration(int memory, std::vector<std::size_t> free,
                                           Eigen::MatrixXd metric, std::vector<double> lower)
    : memory_(memory > 0 ? static_cast<std::size_t>(memory) : 0),
      free_(std::move(free)),
      metric_(std::move(metric)),
      lower_(std::move(lower)) {}

Eigen::VectorXd AndersonAcceleration::FreeOf(const std::vector<double>& k) const {
  Eigen::VectorXd v(static_cast<Eigen::Index>(free_.size()));
  for (std::size_t c = 0; c < free_.size(); ++c) v[static_cast<Eigen::Index>(c)] = k[free_[c]];
  return v;
}

void AndersonAcceleration::Restart() {
  x_.clear();
  g_.clear();
  at_accelerated_ = false;
  contracting_ = 0;
}

std::vector<double> AndersonAcceleration::Next(const std::vector<double>& x, std::vector<double> g,
                                               double step, std::size_t matches) {
  if (memory_ == 0) return g;
  if (at_accelerated_ &&
      (step > last_step_ ||
       static_cast<double>(matches) < kMatchShare * static_cast<double>(last_matches_))) {
    // The accelerated point made ICP step further than the plain point before it, or lost
    // overlap: drop it.
    ++rejected_;
    Restart();
    return last_g_;
  }
  if (!at_accelerated_) {
    // A plain step that does not continue a run of shorter and shorter steps: what came before
    // it is not the linear regime, forget it.
    if (!x_.empty() && step >= last_step_) Restart();
    ++contracting_;
  }
  at_accelerated_ = false;
  last_step_ = step;
  last_matches_ = matches;
  last_g_ = g;
  x_.push_back(FreeOf(x));
  g_.push_back(FreeOf(g));
  if (x_.size() > memory_ + 1) {
    x_.pop_front();
    g_.pop_front();
  }
  const auto m = static_cast<Eigen::Index>(x_.size()) - 1;
  if (m < 1 || contracting_ < kContracting) return g;
  // min |f_last - dF gamma| in the metric, f = G(x) - x; the point is g_last - dG gamma.
  const auto n = static_cast<Eigen::Index>(free_.size());
  Eigen::MatrixXd dF(n, m), dG(n, m);
  for (Eigen::Index j = 0; j < m; ++j) {
    const auto i = static_cast<std::size_t>(j);
    dF.col(j) = (g_[i + 1] - x_[i + 1]) - (g_[i] - x_[i]);
    dG.col(j) = g_[i + 1] - g_[i];
  }
  const Eigen::VectorXd f = g_.back() - x_.back();
  Eigen::MatrixXd normal = dF.transpose() * metric_ * dF;
  // A tiny ridge keeps the solve defined when two residual differences are (nearly) parallel.
  normal.diagonal().array() += 1e-10 * normal.diagonal().maxCoeff() + 1e-300;
  const Eigen::VectorXd gamma = normal.ldlt().solve(dF.transpose() * metric_ * f);
  if (!gamma.allFinite()) return g;
  const Eigen::VectorXd accelerated = g_.back() - dG * gamma;
  for (std::size_t c = 0; c < free_.size(); ++c) {
    const double value = accelerated[static_cast<Eigen::Index>(c)];
    g[free_[c]] = lower_.empty() ? value : std::max(value, lower_[c]);
  }
  at_accelerated_ = true;
  ++accelerated_;
  handed_out_ = g;
  return g;
}

std::vector<double> AndersonAcceleration::Settled(std::vector<double> k_hat) const {
  return at_accelerated_ && k_hat == handed_out_ ? last_g_ : k_hat;
}

}  // namespace selfcal::calib
