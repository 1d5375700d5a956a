// Per-pose cost of T_base_sensor and its 6 x K parameter Jacobian for a 7-joint arm (K = 36):
// plain forward kinematics (the baseline), the analytic one-pass Jacobian, Ceres' ceres::Jet
// automatic differentiation and central differences; the per-point chaining, and the engine's
// point-to-plane row both ways (contracted with the normal first, or through the 3 x K point
// Jacobian). Prints one
// key=value row per method with its time and its ratio to the baseline of the same run.
#include <ceres/jet.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "core/model/jacobian.h"
#include "core/model/kinematics.h"

namespace {

using selfcal::JointType;
constexpr int kParameters = 36;
using Jet = ceres::Jet<double, kParameters>;

template <typename F>
double NanosecondsPer(std::size_t count, F&& body) {
  const auto start = std::chrono::steady_clock::now();
  body();
  const auto end = std::chrono::steady_clock::now();
  return std::chrono::duration<double, std::nano>(end - start).count() / static_cast<double>(count);
}

}  // namespace

int main(int argc, char** argv) {
  const std::size_t poses = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 20000;
  const std::vector<JointType> types(7, JointType::kRevolute);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-2, 2);
  std::vector<double> k(kParameters);
  for (auto& v : k) v = 0.3 * u(rng);
  std::vector<std::vector<double>> q(poses, std::vector<double>(7));
  for (auto& row : q) {
    for (auto& v : row) v = u(rng);
  }
  double sink = 0;  // keeps the optimizer from dropping the work

  const double fk = NanosecondsPer(poses, [&] {
    for (const auto& row : q) {
      sink += selfcal::ForwardKinematics<double, double>(types, k.data(), row.data())(0, 3);
    }
  });
  selfcal::PoseJacobian J;
  const double analytic = NanosecondsPer(poses, [&] {
    for (const auto& row : q) {
      sink += selfcal::ForwardKinematicsWithJacobian(types, k, row, &J)(0, 3) + J(2, 5);
    }
  });
  std::vector<Jet> k_jet(kParameters);
  for (int i = 0; i < kParameters; ++i)
    k_jet[static_cast<std::size_t>(i)] = Jet(k[static_cast<std::size_t>(i)], i);
  const double automatic = NanosecondsPer(poses, [&] {
    for (const auto& row : q) {
      const auto T = selfcal::ForwardKinematics<Jet, double>(types, k_jet.data(), row.data());
      sink += T(0, 3).v[5];
    }
  });
  const double numeric = NanosecondsPer(poses, [&] {
    std::vector<double> k_step = k;
    for (const auto& row : q) {
      for (std::size_t i = 0; i < k.size(); ++i) {
        k_step[i] = k[i] + 1e-6;
        const auto plus =
            selfcal::ForwardKinematics<double, double>(types, k_step.data(), row.data());
        k_step[i] = k[i] - 1e-6;
        const auto minus =
            selfcal::ForwardKinematics<double, double>(types, k_step.data(), row.data());
        k_step[i] = k[i];
        sink += (plus(0, 3) - minus(0, 3)) / 2e-6;
      }
    }
  });
  // Per point: chaining through the pose Jacobian versus transforming the point with jets.
  const std::size_t points = poses * 10;
  selfcal::PointJacobian point(3, kParameters);
  const Eigen::Isometry3d T = selfcal::ForwardKinematicsWithJacobian(types, k, q[0], &J);
  const auto T_jet = selfcal::ForwardKinematics<Jet, double>(types, k_jet.data(), q[0].data());
  const double chain = NanosecondsPer(points, [&] {
    for (std::size_t i = 0; i < points; ++i) {
      const Eigen::Vector3d p(0.001 * static_cast<double>(i % 100), 0.2, 1.0);
      selfcal::ChainPointJacobianRotated(J, T.linear() * p, point);
      sink += point(1, 7);
    }
  });
  const double jet_point = NanosecondsPer(points, [&] {
    for (std::size_t i = 0; i < points; ++i) {
      const Eigen::Vector3d p(0.001 * static_cast<double>(i % 100), 0.2, 1.0);
      const Eigen::Matrix<Jet, 3, 1> p_base = T_jet * p.cast<Jet>();
      sink += p_base(1).v[7];
    }
  });

  // Per point: the engine's point-to-plane row n . d p_base / d k, contracted with the normal
  // before chaining (core/calib/point_to_plane.cc: (n, r x n) . J on the K x 6 transposed Jacobian
  // it stores), against ChainPointJacobian's 3 x K followed by n^T.
  const Eigen::Matrix<double, Eigen::Dynamic, 6> J_transposed = J.transpose();
  Eigen::VectorXd plane_row = Eigen::VectorXd::Zero(kParameters);
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  const double contracted = NanosecondsPer(points, [&] {
    for (std::size_t i = 0; i < points; ++i) {
      const Eigen::Vector3d p(0.001 * static_cast<double>(i % 100), 0.2, 1.0);
      const Eigen::Vector3d r = T.linear() * p;
      Eigen::Matrix<double, 6, 1> w;
      w << n, r.cross(n);
      plane_row.noalias() += J_transposed * w;
    }
  });
  sink += plane_row[7];
  plane_row.setZero();
  const double via_chain = NanosecondsPer(points, [&] {
    for (std::size_t i = 0; i < points; ++i) {
      const Eigen::Vector3d p(0.001 * static_cast<double>(i % 100), 0.2, 1.0);
      selfcal::ChainPointJacobianRotated(J, T.linear() * p, point);
      plane_row.noalias() += point.transpose() * n;
    }
  });
  sink += plane_row[7];

  std::printf("bench=kinematics poses=%zu joints=7 parameters=%d\n", poses, kParameters);
  auto row = [&](const char* method, double ns, double baseline, const char* unit) {
    std::printf("method=%s ns_per_%s=%.1f ratio_to_baseline=%.2f\n", method, unit, ns,
                ns / baseline);
  };
  row("fk_only(baseline)", fk, fk, "pose");
  row("analytic_jacobian", analytic, fk, "pose");
  row("ceres_jet_autodiff", automatic, fk, "pose");
  row("central_differences", numeric, fk, "pose");
  row("point_chain_analytic(baseline)", chain, chain, "point");
  row("point_ceres_jet", jet_point, chain, "point");
  row("point_to_plane_row_contracted(engine)", contracted, chain, "point");
  row("point_to_plane_row_via_chain_point_jacobian", via_chain, chain, "point");
  std::fprintf(stderr, "checksum %g\n", sink);
  return 0;
}
