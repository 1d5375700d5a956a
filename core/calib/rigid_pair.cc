#include "core/calib/rigid_pair.h"

#include <algorithm>
#include <cmath>

#include "core/calib/chain.h"

namespace selfcal::calib {

namespace {

constexpr long kRowsPerBlock = 4096;  // matches stacked before one rank update of M

Eigen::Matrix3d Cross(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// The ray-noise rows (rigid_pair.h) of one block of matches, two per match: sigma (n . R0 ray) and
// its derivative in the free intrinsics.
struct NoiseRows {
  Eigen::VectorXd s0;
  Eigen::MatrixXd B;
  NoiseRows(long matches, long intrinsics) : s0(2 * matches), B(2 * matches, intrinsics) {}
};

// Adds the first `count` noise rows to `noise`.
void AddNoise(const NoiseRows& rows, long count, ExpectedNoise& noise) {
  const auto s0 = rows.s0.head(count);
  const auto B = rows.B.topRows(count);
  noise.v0 += s0.squaredNorm();
  noise.N.noalias() += B.transpose() * B;
  noise.h.noalias() += B.transpose() * s0;
}

// Row `row` of `rows` for the point p (normalized, sensor frame, a depth measure) with its
// derivative D in the intrinsics (PointDerivative) and the match's normal in its sensor frame,
// n_sensor = R0^T n (n including the match's root weight).
void SetNoiseRow(NoiseRows& rows, long row, const Eigen::Vector3d& p, const Eigen::Matrix3d& D,
                 const Eigen::Vector3d& n_sensor, const RayNoise& noise, long m) {
  const double depth = p.z();
  const double sigma = noise.sigma_abs + noise.sigma_rel * depth;
  const Eigen::Vector3d ray = p / depth;
  rows.s0[row] = sigma * n_sensor.dot(ray);
  const Eigen::Matrix3d ray_derivative = (D - ray * D.row(2)) / depth;
  rows.B.row(row) = sigma * (n_sensor.transpose() * ray_derivative).leftCols(m);
}

}  // namespace

RigidPairCost ReduceRigidPair(const PairMatches& matches, CostKind cost,
                              const ProjectedCloud& cloud_i, const ProjectedCloud& cloud_j,
                              const Dataset& dataset_i, const Dataset& dataset_j, double scale,
                              const Eigen::Matrix<double, 3, 4>& T_i,
                              const Eigen::Matrix<double, 3, 4>& T_j,
                              const std::vector<float>& weights,
                              const RigidPairIntrinsics& intrinsics, const RayNoise& noise) {
  RigidPairCost pair;
  pair.dataset_i = matches.dataset_i;
  pair.dataset_j = matches.dataset_j;
  pair.matches = matches.size();
  pair.x0_i = Eigen::Map<const PoseEntries>(T_i.data());
  pair.x0_j = Eigen::Map<const PoseEntries>(T_j.data());
  // Rows a^T of a block of matches, then M += A^T A in one (vectorized) rank update.
  Eigen::Matrix<double, Eigen::Dynamic, 24> A(
      std::min<long>(kRowsPerBlock, static_cast<long>(matches.size())), 24);
  Eigen::VectorXd r0(A.rows());
  const long m = static_cast<long>(intrinsics.intrinsics.Count());
  Eigen::MatrixXd B(m > 0 ? A.rows() : 0, m);  // rows b^T
  pair.C.setZero(24, m);
  pair.N.setZero(m, m);
  pair.h.setZero(m);
  // Only the intrinsics' part of the expected noise is taken out (rigid_pair.h): none without them.
  const bool correct_noise = noise.Any() && m > 0;
  NoiseRows noise_rows(correct_noise ? A.rows() : 0, m);
  if (correct_noise) {
    pair.noise.emplace();
    pair.noise->N.setZero(m, m);
    pair.noise->h.setZero(m);
  }
  for (std::size_t begin = 0; begin < matches.size(); begin += kRowsPerBlock) {
    const long count =
        static_cast<long>(std::min<std::size_t>(kRowsPerBlock, matches.size() - begin));
    for (long k = 0; k < count; ++k) {
      const std::uint32_t u = matches.point_i[begin + static_cast<std::size_t>(k)];
      const std::uint32_t v = matches.point_j[begin + static_cast<std::size_t>(k)];
      const Eigen::Vector3d p_i = NormalizedSensorPoint(dataset_i, u, scale);
      const Eigen::Vector3d p_j = NormalizedSensorPoint(dataset_j, v, scale);
      // sqrt(w) on the row and on r0: M, g and c0 of sum w r^2.
      const double root_weight =
          weights.empty()
              ? 1.0
              : std::sqrt(static_cast<double>(weights[begin + static_cast<std::size_t>(k)]));
      const Eigen::Vector3d n =
          root_weight * MatchNormal(cost, cloud_i, u, cloud_j, v).cast<double>();
      auto a = A.row(k);
      a.segment<3>(0) = (p_i.x() * n).transpose();
      a.segment<3>(3) = (p_i.y() * n).transpose();
      a.segment<3>(6) = (p_i.z() * n).transpose();
      a.segment<3>(9) = (n).transpose();
      a.segment<3>(12) = (-p_j.x() * n).transpose();
      a.segment<3>(15) = (-p_j.y() * n).transpose();
      a.segment<3>(18) = (-p_j.z() * n).transpose();
      a.segment<3>(21) = (-n).transpose();
      r0[k] =
          n.dot((T_i.leftCols<3>() * p_i + T_i.col(3)) - (T_j.leftCols<3>() * p_j + T_j.col(3)));
      if (m > 0) {
        const SensorIntrinsics& model = intrinsics.intrinsics;
        const Eigen::Matrix3d D_i = model.PointDerivative(p_i, intrinsics.values);
        const Eigen::Matrix3d D_j = model.PointDerivative(p_j, intrinsics.values);
        const Eigen::Vector3d n_i = T_i.leftCols<3>().transpose() * n;
        const Eigen::Vector3d n_j = T_j.leftCols<3>().transpose() * n;
        B.row(k) = (n_i.transpose() * D_i - n_j.transpose() * D_j).leftCols(m);
        if (correct_noise) {
          SetNoiseRow(noise_rows, 2 * k, p_i, D_i, n_i, noise, m);
          SetNoiseRow(noise_rows, 2 * k + 1, p_j, D_j, n_j, noise, m);
        }
      }
    }
    const auto rows = A.topRows(count);
    const auto residuals = r0.head(count);
    pair.M.selfadjointView<Eigen::Lower>().rankUpdate(rows.transpose());
    pair.g.noalias() += rows.transpose() * residuals;
    pair.c0 += residuals.squaredNorm();
    if (m > 0) {
      const auto b_rows = B.topRows(count);
      pair.C.noalias() += rows.transpose() * b_rows;
      pair.N.noalias() += b_rows.transpose() * b_rows;
      pair.h.noalias() += b_rows.transpose() * residuals;
    }
    if (correct_noise) AddNoise(noise_rows, 2 * count, *pair.noise);
  }
  pair.M = pair.M.selfadjointView<Eigen::Lower>();
  return pair;
}

void RemoveExpectedNoise(RigidPairCost& pair, double fraction) {
  if (!pair.noise) return;
  pair.N -= fraction * pair.noise->N;
  pair.h -= fraction * pair.noise->h;
  pair.noise.reset();
}

PoseEntriesJacobian PoseEntriesDerivative(
    const Eigen::Matrix<double, 3, 4>& T,
    const Eigen::Matrix<double, 6, Eigen::Dynamic>& jacobian) {
  const auto omega = jacobian.bottomRows<3>();
  PoseEntriesJacobian D(12, jacobian.cols());
  for (int c = 0; c < 3; ++c) D.middleRows<3>(3 * c).noalias() = -Cross(T.col(c)) * omega;
  D.bottomRows<3>() = jacobian.topRows<3>();
  return D;
}

double RigidPairSquaredSum(const RigidPairCost& pair, const PoseEntries& x_i,
                           const PoseEntries& x_j, const Eigen::VectorXd& e,
                           const PoseEntriesJacobian* D_i, const PoseEntriesJacobian* D_j,
                           Eigen::MatrixXd* H, Eigen::VectorXd* gradient) {
  Eigen::Matrix<double, 24, 1> d;
  d << x_i - pair.x0_i, x_j - pair.x0_j;
  const Eigen::Matrix<double, 24, 1> Md = pair.M * d;
  double squared_sum = pair.c0 + 2.0 * pair.g.dot(d) + d.dot(Md);
  const long m = pair.h.size();
  Eigen::Matrix<double, 24, 1> Ce = Eigen::Matrix<double, 24, 1>::Zero();
  if (m > 0) {
    Ce.noalias() = pair.C * e;
    squared_sum += 2.0 * pair.h.dot(e) + 2.0 * d.dot(Ce) + e.dot(pair.N * e);
  }
  if (D_i != nullptr && D_j != nullptr) {
    Eigen::Matrix<double, 24, Eigen::Dynamic> D(24, D_i->cols());
    D.topRows<12>() = *D_i;
    D.bottomRows<12>() = *D_j;
    const Eigen::Matrix<double, 24, Eigen::Dynamic> MD = pair.M * D;
    H->noalias() += D.transpose() * MD;
    gradient->noalias() += D.transpose() * (pair.g + Md + Ce);
    if (m > 0) {  // the intrinsics are the last m columns; D is 0 there
      const Eigen::MatrixXd DC = D.transpose() * pair.C;  // K x m
      H->rightCols(m) += DC;
      H->bottomRows(m) += DC.transpose();
      H->bottomRightCorner(m, m) += pair.N;
      gradient->tail(m) += pair.h + pair.C.transpose() * d + pair.N * e;
    }
  }
  return squared_sum;
}

}  // namespace selfcal::calib
