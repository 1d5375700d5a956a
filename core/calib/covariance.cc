#include "core/calib/covariance.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include "core/model/evaluation.h"
#include "core/model/jacobian.h"
#include "core/model/kinematics.h"

namespace selfcal::calib {
namespace {

constexpr double kNullEigenvalue = 1e-10;  // of the largest, on the unit-diagonal scaling

// H = D S D with S unit-diagonal; eigen-decomposition of S.
struct ScaledEigen {
  Eigen::VectorXd inverse_d;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen;
  double threshold = 0;
};

ScaledEigen Decompose(const Eigen::MatrixXd& hessian) {
  ScaledEigen result;
  const Eigen::VectorXd d = hessian.diagonal().cwiseMax(0.0).cwiseSqrt();
  result.inverse_d = d.unaryExpr([](double x) { return x > 0 ? 1.0 / x : 0.0; });
  const Eigen::MatrixXd scaled =
      result.inverse_d.asDiagonal() * hessian * result.inverse_d.asDiagonal();
  result.eigen.compute(scaled);
  result.threshold = std::max(result.eigen.eigenvalues().maxCoeff(), 0.0) * kNullEigenvalue;
  return result;
}

NormalEquations Zero(long k) {
  NormalEquations zero;
  zero.hessian = Eigen::MatrixXd::Zero(k, k);
  zero.gradient = Eigen::VectorXd::Zero(k);
  return zero;
}

void Add(NormalEquations& sum, const NormalEquations& term) {
  sum.hessian += term.hessian;
  sum.gradient += term.gradient;
  sum.cost += term.cost;
  sum.residuals += term.residuals;
}

// The jackknife over datasets: per dataset, the sum of the pairs that touch it.
Eigen::MatrixXd Jackknife(std::span<const PairNormalEquations> pairs, const NormalEquations& total,
                          std::size_t& scans) {
  const long k = total.hessian.rows();
  std::size_t datasets = 0;
  for (const auto& pair : pairs)
    datasets = std::max({datasets, pair.dataset_i + 1, pair.dataset_j + 1});
  std::vector<NormalEquations> touching(datasets, Zero(k));
  for (const auto& pair : pairs) {
    Add(touching[pair.dataset_i], pair.normal);
    if (pair.dataset_j != pair.dataset_i) Add(touching[pair.dataset_j], pair.normal);
  }
  std::vector<Eigen::VectorXd> steps;
  for (const NormalEquations& scan : touching) {
    if (scan.residuals == 0) continue;
    const Eigen::MatrixXd without = total.hessian - scan.hessian;
    steps.push_back(-PseudoInverse(without) * (total.gradient - scan.gradient));
  }
  scans = steps.size();
  if (scans < 3) return {};
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(k);
  for (const auto& step : steps) mean += step;
  mean /= static_cast<double>(scans);
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Zero(k, k);
  for (const auto& step : steps) covariance += (step - mean) * (step - mean).transpose();
  return covariance * (static_cast<double>(scans - 1) / static_cast<double>(scans));
}

// Position and orientation variance at one configuration: trace(J C J^T) per block.
struct PoseVariance {
  double position = 0, orientation = 0;
};

PoseVariance Propagate(const Eigen::MatrixXd& jacobian, const Eigen::MatrixXd& covariance) {
  const Eigen::MatrixXd propagated = jacobian * covariance * jacobian.transpose();
  return {propagated.topLeftCorner<3, 3>().trace(), propagated.bottomRightCorner<3, 3>().trace()};
}

// The pose Jacobian's columns of the free parameters at one configuration.
Eigen::MatrixXd FreeJacobian(const std::vector<JointType>& types, const std::vector<double>& k,
                             const std::vector<double>& joints,
                             const std::vector<std::size_t>& free) {
  PoseJacobian full;
  ForwardKinematicsWithJacobian(types, k, joints, &full);
  Eigen::MatrixXd jacobian(6, static_cast<long>(free.size()));
  for (std::size_t c = 0; c < free.size(); ++c)
    jacobian.col(static_cast<long>(c)) = full.col(static_cast<long>(free[c]));
  return jacobian;
}

PredictedPoseError Summarize(const std::vector<PoseVariance>& variances) {
  PredictedPoseError error;
  if (variances.empty()) return error;
  double position = 0, orientation = 0;
  for (const PoseVariance& v : variances) {
    position += v.position;
    orientation += v.orientation;
    error.max_position_m = std::max(error.max_position_m, std::sqrt(std::max(v.position, 0.0)));
    error.max_orientation_rad =
        std::max(error.max_orientation_rad, std::sqrt(std::max(v.orientation, 0.0)));
  }
  const double n = static_cast<double>(variances.size());
  error.rms_position_m = std::sqrt(std::max(position / n, 0.0));
  error.rms_orientation_rad = std::sqrt(std::max(orientation / n, 0.0));
  return error;
}

// The bin of kErrorMapBins equal bins over [lower, upper] that `value` falls in.
std::size_t BinOf(double value, double lower, double upper) {
  if (!(upper > lower)) return 0;
  const double bins = static_cast<double>(kErrorMapBins);
  const double bin = std::floor((value - lower) / (upper - lower) * bins);
  return static_cast<std::size_t>(std::clamp(bin, 0.0, bins - 1));
}

JointErrorProfile Profile(const JointSpec& spec, std::size_t joint,
                          const std::vector<std::vector<double>>& configurations,
                          const std::vector<PoseVariance>& sensor,
                          const std::vector<PoseVariance>& flange) {
  JointErrorProfile profile{spec.name,
                            spec.type == JointType::kPrismatic,
                            spec.lower,
                            spec.upper,
                            std::vector<std::size_t>(kErrorMapBins, 0),
                            std::vector<double>(kErrorMapBins, 0.0),
                            std::vector<double>(kErrorMapBins, 0.0)};
  for (std::size_t q = 0; q < configurations.size(); ++q) {
    const std::size_t bin = BinOf(configurations[q][joint], spec.lower, spec.upper);
    ++profile.samples[bin];
    profile.sensor_rms_position_m[bin] += sensor[q].position;
    profile.flange_rms_position_m[bin] += flange[q].position;
  }
  for (std::size_t bin = 0; bin < kErrorMapBins; ++bin) {
    if (profile.samples[bin] == 0) continue;
    const double n = static_cast<double>(profile.samples[bin]);
    profile.sensor_rms_position_m[bin] =
        std::sqrt(std::max(profile.sensor_rms_position_m[bin] / n, 0.0));
    profile.flange_rms_position_m[bin] =
        std::sqrt(std::max(profile.flange_rms_position_m[bin] / n, 0.0));
  }
  return profile;
}

// Each joint's worst bin (a joint without a range has none), the largest first.
std::vector<ErrorRegion> WorstRegions(const std::vector<JointErrorProfile>& joints) {
  std::vector<ErrorRegion> worst;
  for (std::size_t j = 0; j < joints.size(); ++j) {
    const JointErrorProfile& profile = joints[j];
    if (!(profile.upper > profile.lower)) continue;
    const double width = (profile.upper - profile.lower) / static_cast<double>(kErrorMapBins);
    std::optional<ErrorRegion> region;
    for (std::size_t bin = 0; bin < kErrorMapBins; ++bin) {
      if (profile.samples[bin] == 0) continue;
      if (region && profile.sensor_rms_position_m[bin] <= region->sensor_rms_position_m) continue;
      region = ErrorRegion{j, bin, profile.lower + width * static_cast<double>(bin),
                           profile.lower + width * static_cast<double>(bin + 1),
                           profile.sensor_rms_position_m[bin]};
    }
    if (region) worst.push_back(*region);
  }
  std::stable_sort(worst.begin(), worst.end(), [](const ErrorRegion& a, const ErrorRegion& b) {
    return a.sensor_rms_position_m > b.sensor_rms_position_m;
  });
  if (worst.size() > kWorstRegions) worst.resize(kWorstRegions);
  return worst;
}

// The covariance without the tool: its rows and columns zeroed, the marginal of the rest.
Eigen::MatrixXd WithoutTool(const RobotModel& model, const std::vector<std::size_t>& free,
                            const Eigen::MatrixXd& covariance_si) {
  Eigen::MatrixXd robot = covariance_si;
  const std::size_t tool = ToolOffset(model.JointCount());
  for (std::size_t c = 0; c < free.size(); ++c) {
    if (free[c] < tool) continue;
    robot.row(static_cast<long>(c)).setZero();
    robot.col(static_cast<long>(c)).setZero();
  }
  return robot;
}

}  // namespace

Eigen::MatrixXd PseudoInverse(const Eigen::MatrixXd& hessian) {
  const long k = hessian.rows();
  if (k == 0) return {};
  const ScaledEigen decomposition = Decompose(hessian);
  Eigen::MatrixXd scaled_inverse = Eigen::MatrixXd::Zero(k, k);
  for (long e = 0; e < k; ++e) {
    const double value = decomposition.eigen.eigenvalues()[e];
    if (!(value > decomposition.threshold)) continue;
    const Eigen::VectorXd v = decomposition.eigen.eigenvectors().col(e);
    scaled_inverse += v * v.transpose() / value;
  }
  return decomposition.inverse_d.asDiagonal() * scaled_inverse *
         decomposition.inverse_d.asDiagonal();
}

CovarianceEstimate EstimateCovariance(std::span<const PairNormalEquations> pairs) {
  CovarianceEstimate estimate;
  if (pairs.empty()) return estimate;
  const long k = pairs.front().normal.hessian.rows();
  NormalEquations total = Zero(k);
  for (const auto& pair : pairs) Add(total, pair.normal);
  const double dof = static_cast<double>(total.residuals) - static_cast<double>(k);
  const double sigma2 = dof > 0 ? 2.0 * total.cost / dof : 0.0;
  estimate.naive = sigma2 * PseudoInverse(total.hessian);
  estimate.jackknife = Jackknife(pairs, total, estimate.jackknife_scans);
  estimate.reported = estimate.jackknife.size() > 0 ? estimate.jackknife : estimate.naive;
  return estimate;
}

Eigen::MatrixXd ConsiderCovariance(const Eigen::MatrixXd& hessian,
                                   const std::vector<long>& estimated,
                                   const std::vector<long>& held, const Eigen::VectorXd& held_sd) {
  const long e = static_cast<long>(estimated.size()), h = static_cast<long>(held.size());
  Eigen::MatrixXd h_ee(e, e), h_eh(e, h);
  for (long i = 0; i < e; ++i) {
    const long row = estimated[static_cast<std::size_t>(i)];
    for (long j = 0; j < e; ++j) h_ee(i, j) = hessian(row, estimated[static_cast<std::size_t>(j)]);
    for (long j = 0; j < h; ++j) h_eh(i, j) = hessian(row, held[static_cast<std::size_t>(j)]);
  }
  const Eigen::MatrixXd sensitivity = -PseudoInverse(h_ee) * h_eh;  // d estimate / d held
  return sensitivity * held_sd.cwiseAbs2().asDiagonal() * sensitivity.transpose();
}

Eigen::MatrixXd ToSiUnits(const Eigen::MatrixXd& covariance, const std::vector<bool>& translation,
                          double scale) {
  Eigen::VectorXd d(static_cast<long>(translation.size()));
  for (std::size_t c = 0; c < translation.size(); ++c)
    d[static_cast<long>(c)] = translation[c] ? scale : 1.0;
  return d.asDiagonal() * covariance * d.asDiagonal();
}

PredictedError PredictPoseError(const RobotModel& model, const std::vector<std::size_t>& free,
                                const Eigen::MatrixXd& covariance_si,
                                const std::vector<std::vector<double>>& configurations) {
  PredictedError result;
  result.samples = configurations.size();
  const std::vector<double> k = ToParameterVector(model);
  const std::vector<JointType> types = JointTypes(model);
  const Eigen::MatrixXd robot = WithoutTool(model, free, covariance_si);
  std::vector<PoseVariance> sensor, flange;
  for (const auto& joints : configurations) {
    const Eigen::MatrixXd jacobian = FreeJacobian(types, k, joints, free);
    sensor.push_back(Propagate(jacobian, covariance_si));
    flange.push_back(Propagate(jacobian, robot));
  }
  result.sensor = Summarize(sensor);
  result.flange = Summarize(flange);
  if (configurations.empty()) return result;
  for (std::size_t j = 0; j < model.JointCount(); ++j)
    result.map.joints.push_back(Profile(model.joints[j], j, configurations, sensor, flange));
  result.map.worst = WorstRegions(result.map.joints);
  return result;
}

PredictedError PredictPoseError(const RobotModel& model, const std::vector<std::size_t>& free,
                                const Eigen::MatrixXd& covariance_si, std::size_t samples,
                                std::uint64_t seed) {
  PredictedError result =
      PredictPoseError(model, free, covariance_si, RandomConfigurations(model, samples, seed));
  result.seed = seed;
  return result;
}

namespace {

// The parameters that dominate `direction` (normalized units), "A1->A2.x, A2->A3.alpha".
UnobservableFinding Dominant(const Eigen::VectorXd& direction, const RobotModel& model,
                             const std::vector<std::size_t>& free) {
  const double largest = direction.cwiseAbs().maxCoeff();
  UnobservableFinding finding;
  for (long c = 0; c < direction.size(); ++c) {
    if (std::abs(direction[c]) < 0.3 * largest) continue;
    finding.text += (finding.text.empty() ? "" : ", ") +
                    ParameterName(model, free[static_cast<std::size_t>(c)]);
    finding.parameters.push_back(static_cast<std::size_t>(c));
  }
  return finding;
}

// Exact rank deficiency: the null space of H that moves the sensor (the rest is a redundancy
// of the parametrization), one entry per parameter with most of its unit vector in it.
void NameNullSpace(const Eigen::MatrixXd& hessian, const Eigen::MatrixXd& pose,
                   const RobotModel& model, const std::vector<std::size_t>& free,
                   std::vector<UnobservableFinding>& out) {
  const long k = hessian.rows();
  const ScaledEigen decomposition = Decompose(hessian);
  std::vector<long> null;
  for (long e = 0; e < k; ++e) {
    if (!(decomposition.eigen.eigenvalues()[e] > decomposition.threshold)) null.push_back(e);
  }
  if (null.empty()) return;
  Eigen::MatrixXd basis(k, static_cast<long>(null.size()));
  for (std::size_t n = 0; n < null.size(); ++n)
    basis.col(static_cast<long>(n)) = decomposition.eigen.eigenvectors().col(null[n]);
  // A parameter the scans do not touch has a zero row of H: its own null direction.
  Eigen::MatrixXd directions = decomposition.inverse_d.asDiagonal() * basis;
  for (long c = 0; c < k; ++c) {
    if (decomposition.inverse_d[c] == 0) directions.row(c) = basis.row(c);
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(pose * directions, Eigen::ComputeFullV);
  Eigen::MatrixXd moving(k, 0);
  for (long i = 0; i < svd.singularValues().size(); ++i) {
    if (svd.singularValues()[i] < 1e-6) continue;
    moving.conservativeResize(k, moving.cols() + 1);
    moving.col(moving.cols() - 1) = basis * svd.matrixV().col(i);
  }
  for (long c = 0; c < k && moving.cols() > 0; ++c) {
    const double share = moving.row(c).squaredNorm();  // of its unit vector, in the null space
    if (share < 0.5) continue;
    char text[96];
    std::snprintf(text, sizeof(text),
                  ": not observable from these scans (%.0f %% of it in the "
                  "null space of J^T J)",
                  share * 100);
    out.push_back({ParameterName(model, free[static_cast<std::size_t>(c)]) + text,
                   {static_cast<std::size_t>(c)}});
  }
}

// Directions the covariance leaves the sensor position free to move along by more than
// kUnobservableMotion (RMS over the configurations): what the scans do not pin down.
void NameWeakDirections(const Eigen::MatrixXd& covariance, const Eigen::MatrixXd& pose,
                        double scale, const RobotModel& model, const std::vector<std::size_t>& free,
                        std::vector<UnobservableFinding>& out) {
  const long k = covariance.rows();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> spread(covariance);
  const Eigen::VectorXd roots = spread.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  const Eigen::MatrixXd root =
      spread.eigenvectors() * roots.asDiagonal() * spread.eigenvectors().transpose();  // C^1/2
  Eigen::MatrixXd position(pose.rows() / 2, k);  // the position rows, in m
  for (long q = 0; q < pose.rows() / 6; ++q)
    position.middleRows(3 * q, 3) = pose.middleRows(6 * q, 3) * scale;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> motion(root * position.transpose() * position *
                                                        root);
  for (long e = k - 1; e >= 0; --e) {
    const double metres = std::sqrt(std::max(motion.eigenvalues()[e], 0.0));
    if (metres <= kUnobservableMotion) break;
    char text[96];
    std::snprintf(text, sizeof(text),
                  ": not observable from these scans (together %.1f mm of "
                  "sensor position, 1 sigma RMS)",
                  metres * 1e3);
    UnobservableFinding finding = Dominant(root * motion.eigenvectors().col(e), model, free);
    finding.text += text;
    out.push_back(std::move(finding));
  }
}

// The pose Jacobian over sample configurations, stacked, in normalized units (positions / s),
// divided by sqrt(configurations): how far a change of the free parameters moves the sensor.
Eigen::MatrixXd StackedPoseJacobian(const RobotModel& model, const std::vector<std::size_t>& free,
                                    double scale) {
  const auto configurations = RandomConfigurations(model, 50, kPredictionSeed);
  const std::vector<double> parameters = ToParameterVector(model);
  const std::vector<JointType> types = JointTypes(model);
  const long k = static_cast<long>(free.size());
  Eigen::MatrixXd pose(6 * static_cast<long>(configurations.size()), k);
  for (std::size_t q = 0; q < configurations.size(); ++q) {
    PoseJacobian full;
    ForwardKinematicsWithJacobian(types, parameters, configurations[q], &full);
    for (long c = 0; c < k; ++c) {
      const std::size_t index = free[static_cast<std::size_t>(c)];
      Eigen::Matrix<double, 6, 1> column = full.col(static_cast<long>(index));
      if (IsTranslationParameter(model, index)) column *= scale;
      column.head<3>() /= scale;
      pose.block<6, 1>(6 * static_cast<long>(q), c) = column;
    }
  }
  return pose / std::sqrt(static_cast<double>(configurations.size()));
}

}  // namespace

std::vector<UnobservableFinding> FindUnobservable(const Eigen::MatrixXd& hessian,
                                                  const Eigen::MatrixXd& covariance,
                                                  const RobotModel& model,
                                                  const std::vector<std::size_t>& free,
                                                  double scale) {
  std::vector<UnobservableFinding> unobservable;
  if (hessian.rows() == 0) return unobservable;
  const Eigen::MatrixXd pose = StackedPoseJacobian(model, free, scale);
  NameNullSpace(hessian, pose, model, free, unobservable);
  if (covariance.rows() == hessian.rows())
    NameWeakDirections(covariance, pose, scale, model, free, unobservable);
  return unobservable;
}

std::vector<std::string> UnobservableParameters(const Eigen::MatrixXd& hessian,
                                                const Eigen::MatrixXd& covariance,
                                                const RobotModel& model,
                                                const std::vector<std::size_t>& free,
                                                double scale) {
  std::vector<std::string> names;
  for (auto& finding : FindUnobservable(hessian, covariance, model, free, scale))
    names.push_back(std::move(finding.text));
  return names;
}

Eigen::MatrixXd MeanPositionGram(const RobotModel& model, const std::vector<std::size_t>& free,
                                 const std::vector<std::vector<double>>& configurations) {
  const long k = static_cast<long>(free.size());
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(k, k);
  if (configurations.empty()) return gram;
  const std::vector<double> parameters = ToParameterVector(model);
  const std::vector<JointType> types = JointTypes(model);
  for (const auto& joints : configurations) {
    const Eigen::MatrixXd position = FreeJacobian(types, parameters, joints, free).topRows(3);
    gram += position.transpose() * position;
  }
  return gram / static_cast<double>(configurations.size());
}

}  // namespace selfcal::calib
