// The parameter covariance of a calibration and what it predicts for the sensor pose.
//
// The textbook covariance sigma^2 (J^T J)^-1 treats every match as an independent measurement.
// Matches are not: all matches of a stationary scan share that scan's pose error (encoder noise,
// model error the MCPC form cannot express), neighbouring residuals share their normals' noise,
// and a depth image gives a hundred thousand matches from a few dozen poses. The naive covariance
// is then far too small (5 to 35 times on the simulated scenarios, docs/engine.md). We estimate it
// instead by a jackknife over the fit scans, linearized at the solution: leaving scan s out
// removes the normal equations of every pair touching it, H_-s = H - H_s, g_-s = g - g_s, and one
// Gauss-Newton step from the solution gives that fit's parameters, d_s = -H_-s^+ g_-s. The spread
// of the d_s over the S scans, (S - 1) / S sum (d_s - mean)(d_s - mean)^T, is the jackknife
// covariance (consistent for statistics over pairs of units, as a pair of scans is here). It
// sees whatever makes scans disagree, whatever its correlation inside a scan.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/calib/point_to_plane.h"
#include "core/calib/predicted_error.h"
#include "core/model/robot_model.h"

namespace selfcal::calib {

// The normal equations of the matches of one pair of fit datasets (indices into the datasets).
struct PairNormalEquations {
  std::size_t dataset_i = 0, dataset_j = 0;
  NormalEquations normal;
};

struct CovarianceEstimate {
  Eigen::MatrixXd naive;      // sigma^2 H^+, sigma^2 = sum r^2 / (N - K); normalized units
  Eigen::MatrixXd jackknife;  // over the fit scans; empty with fewer than 3 scans
  std::size_t jackknife_scans = 0;
  // What the result reports: the jackknife's when there is one, else the naive one.
  Eigen::MatrixXd reported;
};

// The pseudo-inverse of a symmetric positive semi-definite H, computed on its unit-diagonal
// scaling so that units do not matter; eigenvalues below 1e-10 of the largest count as zero.
Eigen::MatrixXd PseudoInverse(const Eigen::MatrixXd& hessian);

// `pairs`: the fit pairs' normal equations at the solution (all over the same free parameters).
CovarianceEstimate EstimateCovariance(std::span<const PairNormalEquations> pairs);

// The consider covariance (Schmidt): what the uncertainty of quantities the calibration holds at
// assumed values (the sensor's intrinsics, HeldIntrinsics) does to the estimate. No scan can show
// an error common to all of them; a jackknife sees only what makes scans disagree. `hessian` is
// J^T J over the estimated parameters and the held ones at the solution; rows `estimated` (in the
// covariance's order) and `held` index it. The estimate moves by G = -H_ee^+ H_eh per unit of
// the held values, so its covariance grows by G diag(held_sd^2) G^T (same units as `hessian`).
Eigen::MatrixXd ConsiderCovariance(const Eigen::MatrixXd& hessian,
                                   const std::vector<long>& estimated,
                                   const std::vector<long>& held, const Eigen::VectorXd& held_sd);

// Normalized to SI: translations scaled by s (`translation[c]` true for free parameter c).
Eigen::MatrixXd ToSiUnits(const Eigen::MatrixXd& covariance, const std::vector<bool>& translation,
                          double scale);

// `covariance_si` is over the flat parameters `free` of `model` (SI units): the predicted
// sensor and flange error and its map over the joint space, on `samples` configurations drawn
// by RandomConfigurations(model, samples, seed), or on the given ones (seed 0).
PredictedError PredictPoseError(const RobotModel& model, const std::vector<std::size_t>& free,
                                const Eigen::MatrixXd& covariance_si,
                                const std::vector<std::vector<double>>& configurations);
PredictedError PredictPoseError(const RobotModel& model, const std::vector<std::size_t>& free,
                                const Eigen::MatrixXd& covariance_si, std::size_t samples,
                                std::uint64_t seed);

// A direction of parameter space the scans leave the sensor position free to move along by
// more than this (1 sigma, RMS over the workspace) is not observed in any useful sense.
inline constexpr double kUnobservableMotion = 0.01;  // m

// The calibrated parameters the scans cannot determine, each "names: not observable from these
// scans (why)", from the normal equations H and the covariance C (both normalized units):
//  - the null space of H (eigenvalues of its unit-diagonal scaling below 1e-10 of the largest)
//    as far as it moves the sensor: a parameter with most of its unit vector in it is named. A
//    null direction that moves no sensor pose is a redundancy of the parametrization (tool alpha
//    and gamma at beta = -90 deg turn about the same axis), not of the scans;
//  - the directions along which C lets the sensor position move by more than
//    kUnobservableMotion (eigen-directions of C^1/2 P^T P C^1/2, P the position Jacobian over
//    the configurations), named by their dominant parameters. Noise in the normals gives a
//    scene that cannot observe a parameter (one plane) spurious information, so H is seldom
//    exactly singular there; the jackknife's C sees that the scans disagree.
std::vector<std::string> UnobservableParameters(const Eigen::MatrixXd& hessian,
                                                const Eigen::MatrixXd& covariance,
                                                const RobotModel& model,
                                                const std::vector<std::size_t>& free, double scale);
// The same findings with the parameters each names (indices into `free`), for a caller that
// masks them (the scan planner, core/plan/information_planner.h).
struct UnobservableFinding {
  std::string text;                     // as UnobservableParameters gives it
  std::vector<std::size_t> parameters;  // into `free`
};
std::vector<UnobservableFinding> FindUnobservable(const Eigen::MatrixXd& hessian,
                                                  const Eigen::MatrixXd& covariance,
                                                  const RobotModel& model,
                                                  const std::vector<std::size_t>& free,
                                                  double scale);

// G = mean over `configurations` of P^T P, P the 3 x K sensor position Jacobian of the free
// parameters (SI): the predicted sensor position RMS of a covariance C (SI) is
// sqrt(trace(C G)), PredictPoseError's sensor.rms_position_m, in K x K operations per C.
Eigen::MatrixXd MeanPositionGram(const RobotModel& model, const std::vector<std::size_t>& free,
                                 const std::vector<std::vector<double>>& configurations);

}  // namespace selfcal::calib
