// The matches between two scans taken in one pose each (depth cameras), reduced once per ICP
// iteration to the exact quadratic form of their cost in the two poses.
//
// With the normal n held fixed (point_to_plane.h), a match's residual
//   r = n . (R_i p_i + t_i - R_j p_j - t_j)
// is linear in the pose entries x = [vec(R_i); t_i; vec(R_j); t_j] (24 numbers):
//   r = r0 + a^T (x - x0),   a = [p_i (x) n; n; -p_j (x) n; -n],
// r0 its value at the poses x0 of the matching. So over all matches of the pair, with d = x - x0,
//   sum r^2 = c0 + 2 g^T d + d^T M d,   M = sum a a^T, g = sum a r0, c0 = sum r0^2,
// for any parameters k: every Levenberg-Marquardt evaluation costs O(1) per pair instead of
// O(matches), and the matches need not be kept at all (memory bounded by the points, not by the
// matches). The chain rule through d x / d k (from the pose's 6 x K Jacobian) gives
// J^T J = D^T M D and J^T r = D^T (g + M d).
//
// The sensor intrinsics (sensor_intrinsics.h) add e = theta_hat - theta_hat0, the change of their
// free values since the matching, through the derivative b of each residual:
//   r = r0 + a^T d + b^T e,   b_c = n . (R0_i D_i,c - R0_j D_j,c),
// D the point's derivative (PointDerivative) and R0 the rotations of the matching, held fixed
// like the normal: a change of R times a change of theta is left out. The ICP iteration that
// follows re-reduces at the new estimate, so the fixed point is the true cost's stationary point.
// C = sum a b^T, N = sum b b^T and h = sum b r0 (empty without intrinsics).
//
// DELIBERATE DEVIATION (docs/engine.md, deviation 23), on request (RayNoise): the noise of a range
// sensor lies along its rays. A point p = ray * m measured with noise e of sigma(m) puts
// (n . R ray) e into the residual, so the expected sum of squares holds
//   v = sigma_i^2 (n . R_i ray_i)^2 + sigma_j^2 (n . R_j ray_j)^2
// per match: a term that does not measure how well the scans agree, yet changes with the focal
// length (through ray) and the rotations. Least squares lowers it by narrowing the rays (a focal
// length found short). With free intrinsics the reduction also gathers v's dependence on them at
// the matching's poses (ExpectedNoise): rows s = sigma n . R0 ray and their derivative
// sigma n . R0 d ray / d theta, N_v and h_v as N and h above, v0 = sum s^2.
// RemoveExpectedNoise takes a fraction of it out of N and h (a corrected score). The rotations'
// part stays: taken out as well, it let a poorly observed rotation of the scans run away
// (kinect-bunny twin, seed 4: 50 iterations and 39.6 mm). c0 stays the plain sum of squares.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/calib/dataset.h"
#include "core/calib/matching.h"
#include "core/calib/projection.h"

namespace selfcal::calib {

using PoseEntries = Eigen::Matrix<double, 12, 1>;  // vec of a 3 x 4 [R t], column-major
using PoseEntriesJacobian = Eigen::Matrix<double, 12, Eigen::Dynamic>;  // d x / d k (free columns)

// The expected noise's intrinsics part N_v, h_v and its sum v0 at the matching.
struct ExpectedNoise {
  Eigen::MatrixXd N;
  Eigen::VectorXd h;
  double v0 = 0;
};

struct RigidPairCost {
  std::uint32_t dataset_i = 0, dataset_j = 0;
  std::size_t matches = 0;
  Eigen::Matrix<double, 24, 24> M = Eigen::Matrix<double, 24, 24>::Zero();
  Eigen::Matrix<double, 24, 1> g = Eigen::Matrix<double, 24, 1>::Zero();
  double c0 = 0;
  Eigen::Matrix<double, 24, Eigen::Dynamic> C;  // 24 x intrinsics.Count()
  Eigen::MatrixXd N;
  Eigen::VectorXd h;
  PoseEntries x0_i = PoseEntries::Zero(), x0_j = PoseEntries::Zero();
  // The expected noise's intrinsics part (RayNoise with free intrinsics only).
  std::optional<ExpectedNoise> noise;
};

// Takes `fraction` of pair.noise out of its cost (rigid_pair.h, deviation 23) and drops it.
void RemoveExpectedNoise(RigidPairCost& pair, double fraction);

// Reduces `matches` at the poses T_i, T_j (normalized units), each with the normal MatchNormal()
// gives for `cost` from the clouds projected at those poses. `weights` (one per match, or empty
// for all 1: the robust loss's, robust_loss.h) multiply each match's a a^T, a r0 and r0^2, so the
// reduction is that of sum w r^2, exact for weights held fixed. `intrinsics` (may be empty) and
// their values at the matching, normalized (SensorIntrinsics::Values(theta_hat, 1)), give b.
struct RigidPairIntrinsics {
  SensorIntrinsics intrinsics;
  IntrinsicValues values = IntrinsicValues::Zero();
};
// The sensor's noise along its rays, sigma = sigma_abs + sigma_rel * depth, normalized units;
// both 0: no correction (the paper's sum of squares).
struct RayNoise {
  double sigma_abs = 0;
  double sigma_rel = 0;
  bool Any() const { return sigma_abs > 0 || sigma_rel > 0; }
};
RigidPairCost ReduceRigidPair(const PairMatches& matches, CostKind cost,
                              const ProjectedCloud& cloud_i, const ProjectedCloud& cloud_j,
                              const Dataset& dataset_i, const Dataset& dataset_j, double scale,
                              const Eigen::Matrix<double, 3, 4>& T_i,
                              const Eigen::Matrix<double, 3, 4>& T_j,
                              const std::vector<float>& weights = {},
                              const RigidPairIntrinsics& intrinsics = {},
                              const RayNoise& noise = {});

// d x / d k for a pose T with Jacobian J (rows d t, omega; core/model/jacobian.h):
// d r_c = omega x r_c for every column r_c of R, and d t itself.
PoseEntriesJacobian PoseEntriesDerivative(const Eigen::Matrix<double, 3, 4>& T,
                                          const Eigen::Matrix<double, 6, Eigen::Dynamic>& jacobian);

// sum r^2 at poses x_i, x_j and intrinsics change e (pair.h.size() entries, the last free
// parameters), and when D_i, D_j are given, adds J^T J and J^T r to H, gradient.
double RigidPairSquaredSum(const RigidPairCost& pair, const PoseEntries& x_i,
                           const PoseEntries& x_j, const Eigen::VectorXd& e,
                           const PoseEntriesJacobian* D_i, const PoseEntriesJacobian* D_j,
                           Eigen::MatrixXd* H, Eigen::VectorXd* gradient);

}  // namespace selfcal::calib
