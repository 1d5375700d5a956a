#include "core/calib/calibrate.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <utility>

#include "core/calib/anderson_acceleration.h"
#include "core/calib/chain.h"
#include "core/calib/covariance.h"
#include "core/calib/joint_correction.h"
#include "core/calib/observability.h"
#include "core/calib/pair_information.h"
#include "core/calib/pair_matching.h"
#include "core/calib/parallel.h"
#include "core/calib/point_to_plane.h"
#include "core/calib/projection.h"
#include "core/calib/reference_solver.h"
#include "core/calib/robust_loss.h"
#include "core/calib/sensor_motion.h"
#include "core/calib/termination.h"
#include "core/model/kinematics.h"
#include "core/model/normalization.h"

namespace selfcal::calib {

const char* SearchName(SearchStrategy search) { return kSearchNames.Name(search); }
const char* SolverName(SolverKind kind) { return kSolverNames.Name(kind); }
const char* CostName(CostKind cost) { return kCostNames.Name(cost); }
const char* NormalName(NormalKind normals) { return kNormalNames.Name(normals); }
const char* LossName(LossKind loss) { return kLossNames.Name(loss); }

const char* StepMeasureLabel(StepMeasure measure) {
  return measure == StepMeasure::kSensor ? "sensor step" : "|delta k|";
}

const char* TerminationName(Termination termination) {
  switch (termination) {
    case Termination::kConverged:
      return "converged";
    case Termination::kMaxIterations:
      return "max_iterations";
    case Termination::kCancelled:
      return "cancelled";
    case Termination::kTooFewMatches:
      return "too_few_matches";
    case Termination::kSolverFailed:
      return "solver_failed";
    case Termination::kInvalidInput:
      return "invalid_input";
  }
  return "unknown";
}

const char* StageName(CalibrationStage stage) {
  switch (stage) {
    case CalibrationStage::kValidation:
      return "validation";
    case CalibrationStage::kMatching:
      return "matching";
    case CalibrationStage::kSolving:
      return "solving";
    case CalibrationStage::kIterationDone:
      return "iteration done";
    case CalibrationStage::kCovariance:
      return "covariance";
  }
  return "unknown";
}

namespace {

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string CheckDatasets(const std::vector<Dataset>& datasets, const RobotModel& nominal) {
  for (const Dataset& dataset : datasets) {
    const std::string scan = "scan " + std::to_string(dataset.scan_index);
    if (dataset.joint_count != nominal.JointCount()) {
      return scan + ": " + std::to_string(dataset.joint_count) + " joints, the robot model has " +
             std::to_string(nominal.JointCount());
    }
    const std::size_t points = dataset.PointCount();
    if (dataset.x.size() != points || dataset.y.size() != points || dataset.z.size() != points) {
      return scan + ": point arrays do not match its " + std::to_string(dataset.rows) + " x " +
             std::to_string(dataset.cols) + " grid";
    }
    if (!dataset.HasJointsOfEveryPose()) {
      return scan + ": " + std::to_string(dataset.pose_joints.size()) + " joint values for " +
             std::to_string(dataset.PoseCount()) + " poses";
    }
    const std::vector<double>& joints =
        dataset.pose_joints.empty() ? dataset.joint_states->positions : dataset.pose_joints;
    for (double value : joints) {
      if (!std::isfinite(value)) return scan + ": joint positions contain NaN or infinity";
    }
    if (dataset.ValidPointCount() == 0) return scan + ": no valid points";
  }
  return {};
}

// The robot model and the datasets are consistent with each other; counts the scans and points
// into `result`. Returns what is wrong, or nothing.
std::string CheckInput(const std::vector<Dataset>& datasets, const RobotModel& nominal,
                       CalibrationResult& result) {
  if (const std::string problem = CheckConsistency(nominal); !problem.empty()) {
    return "robot model: " + problem;
  }
  if (nominal.JointCount() > kMaxJoints) return "robot model has more than 16 joints";
  if (std::string problem = CheckDatasets(datasets, nominal); !problem.empty()) return problem;
  for (const Dataset& dataset : datasets) {
    result.fit_scans += dataset.validation ? 0 : 1;
    result.validation_scans += dataset.validation ? 1 : 0;
    result.points += dataset.PointCount();
  }
  if (result.fit_scans < 2) {
    return "need at least two fit scans, got " + std::to_string(result.fit_scans);
  }
  for (bool free : nominal.mask) {
    if (free) return {};
  }
  return "the mask selects no parameter to calibrate";
}

struct Rms {
  std::size_t matches = 0;
  double rms_m = 0;
};

// sqrt(sum r^2 / N), in metres, from 1/2 sum r^2 in normalized units.
// `residuals`: their count, or the sum of their weights (robust_loss.h).
double RmsFromCost(double cost, double residuals, double scale) {
  return std::sqrt(2.0 * cost / residuals) * scale;
}

// What the calibration holds at assumed values although they are uncertain (deviation 21): the
// sensor's intrinsics at the file's values and, for a rigid model whose robot file gives their
// uncertainty, the joints' compliance at 0.
struct HeldParameters {
  HeldIntrinsics intrinsics;
  JointCorrection elasticity;         // its columns only, at compliance 0
  std::vector<double> elasticity_sd;  // per column, in theta_hat units (joint_correction.h)
  bool Empty() const { return intrinsics.Empty() && elasticity.ElasticityCount() == 0; }
};

// The state of one calibration: the normalized chain, every dataset's pose knots and the two
// stages of an iteration, data association (PairMatcher) and the cost (MatchProblem).
class Icp {
 public:
  // With intrinsics, `corrected` is `datasets` itself, whose points the calibration keeps
  // corrected at the current estimate (sensor_intrinsics.h); else null.
  Icp(const std::vector<Dataset>& datasets, std::vector<Dataset>* corrected,
      const RobotModel& nominal, const CalibrationOptions& options, double scale,
      JointCorrection correction, SensorIntrinsics intrinsics, int threads,
      const ProgressCallback& progress, const std::atomic<bool>* cancel)
      : datasets_(datasets),
        corrected_(corrected),
        options_(options),
        threads_(threads),
        progress_(progress),
        cancel_(cancel),
        chain_(MakeChain(nominal, scale, std::move(correction), intrinsics)),
        free_(FreeParameters(nominal, chain_.correction.Count() + intrinsics.Count())),
        knots_(BuildAllPoseKnots(datasets, threads, options.knot_max_joint_step)),
        matcher_(datasets, chain_, knots_, options, threads),
        problem_(datasets, chain_, knots_, free_, threads,
                 options.solver == SolverKind::kReference,  // Ceres needs every match
                 options.cost),
        fit_pairs_(AllPairs(Selected(datasets, false))),
        validation_pairs_(PairsTouching(Selected(datasets, true))),
        loss_(MakeRobustLoss(options, scale)),
        motion_(chain_, free_, datasets),
        lower_(LowerBounds(chain_.correction, chain_.ParameterCount(), free_)) {
    problem_.SetLoss(loss_);  // the fit's loss; validation measures the paper's plain RMS
    if (options.ray_noise_correction) {
      problem_.SetRayNoise({options.sigma_abs / scale, options.sigma_rel});
    }
  }

  void Report(int iteration, CalibrationStage stage, std::size_t matches, double delta) const {
    if (progress_) progress_({iteration, options_.i_max, stage, matches, delta});
  }

  // Algorithm 1's loop body at k_hat: project, filter, match and reject, then solve. Returns the
  // report and the new parameters, or why the calibration stops here.
  struct Outcome {
    IterationReport report;
    std::vector<double> k_hat;
    std::optional<Stop> stop;
  };
  Outcome RunIteration(int iteration, const std::vector<double>& k_hat,
                       const TerminationCriterion& criterion);

  // Point-to-plane RMS of the pairs touching a validation scan at `k_hat`.
  Rms Validate(const std::vector<double>& k_hat);
  // After Validate(k_hat): every held-out scan registered rigidly onto the fit scans.
  // Consumes the clouds the validation projected (the next Prepare() makes them again).
  HeldOutRegistration RegisterHeldOut() {
    return RegisterHeldOutScans(datasets_, matcher_.TakeClouds(), options_.d_max, options_.f_min,
                                options_.reject_coverage_border, chain_.scale, threads_);
  }
  // J^T J and the cost of the fit matches made at the solution, one term per pair of scans (for
  // the covariance's jackknife over scans), over the free parameters and the held ones at their
  // assumed values (for the consider covariance, covariance.h).
  struct SolutionInformation {
    std::vector<PairNormalEquations> pairs;
    std::vector<long> estimated, held;  // their rows: the free parameters in order; the held ones
    Eigen::VectorXd held_sd;            // normalized units
  };
  SolutionInformation LinearizePairsAtSolution(const std::vector<double>& k_hat,
                                               const HeldParameters& held);
  const std::vector<std::size_t>& free() const { return free_; }
  const std::vector<double>& lower() const { return lower_; }
  std::size_t PointsOnLinks() const { return matcher_.PointsOnLinksCount(); }
  const Chain& chain() const { return chain_; }
  const SensorMotion& motion() const { return motion_; }
  void SetQueryStride(int stride) { matcher_.SetQueryStride(stride); }
  // After the loop: the covariance and the validation make their own matches.
  void ReleaseFitMatches() { problem_.Clear(); }

 private:
  static Chain MakeChain(const RobotModel& nominal, double scale, JointCorrection correction,
                         SensorIntrinsics intrinsics) {
    Chain chain = ChainOf(nominal, scale);
    chain.correction = std::move(correction);
    chain.intrinsics = intrinsics;
    return chain;
  }
  // The masked MCPC parameters, then every parameter beyond them (joint correction, intrinsics).
  static std::vector<std::size_t> FreeParameters(const RobotModel& nominal, std::size_t beyond) {
    std::vector<std::size_t> free;
    for (std::size_t i = 0; i < nominal.mask.size(); ++i) {
      if (nominal.mask[i]) free.push_back(i);
    }
    for (std::size_t c = 0; c < beyond; ++c) free.push_back(nominal.mask.size() + c);
    return free;
  }
  // The points corrected at k_hat's intrinsics, and the joint correction's G(q) evaluated at the
  // estimate `k_hat` until the next call (joint_correction.h): once per ICP iteration, held fixed
  // through its solve.
  void Freeze(const std::vector<double>& k_hat) {
    CorrectIntrinsics(k_hat);
    if (chain_.correction.Empty()) return;
    std::vector<double> k(k_hat.begin(),
                          k_hat.begin() + static_cast<std::ptrdiff_t>(chain_.ParameterCount()));
    DenormalizeTranslationParameters(k, chain_.JointCount(), chain_.scale);
    chain_.correction.frozen_parameters = std::move(k);
  }
  void CorrectIntrinsics(const std::vector<double>& k_hat) {
    if (corrected_ == nullptr) return;
    const IntrinsicValues values =
        chain_.intrinsics.Values(chain_.FreeIntrinsics(k_hat.data()), chain_.scale);
    if (values == applied_intrinsics_) return;
    ParallelFor(corrected_->size(), threads_, [&](std::size_t d) {
      CorrectPoints(chain_.intrinsics.measure, applied_intrinsics_, values, (*corrected_)[d]);
    });
    applied_intrinsics_ = values;
    matcher_.PointsMoved();
  }
  static std::vector<bool> Selected(const std::vector<Dataset>& datasets, bool validation) {
    std::vector<bool> selected(datasets.size());
    for (std::size_t d = 0; d < datasets.size(); ++d)
      selected[d] = datasets[d].validation == validation;
    return selected;
  }
  // Projection, normals and filter at `k_hat`, then matching and rejection into `target`.
  void MatchInto(MatchProblem& target, const std::vector<DatasetPair>& pairs,
                 const std::vector<double>& k_hat) {
    matcher_.Prepare(k_hat, pairs);
    target.SetMatches(
        pairs, [&](std::size_t p) { return matcher_.MatchPair(pairs[p]); }, matcher_.clouds(),
        k_hat);
  }
  std::vector<int> UnmatchedFitScans() const {
    std::vector<int> scans;
    for (std::size_t d = 0; d < datasets_.size(); ++d) {
      if (!datasets_[d].validation && problem_.MatchesPerDataset()[d] == 0)
        scans.push_back(datasets_[d].scan_index);
    }
    return scans;
  }
  bool Solve(std::vector<double>& k_hat, LmSummary& summary) const {
    return options_.solver == SolverKind::kFast
               ? SolveLevenbergMarquardt(problem_, options_.lm_max_iterations, k_hat, summary,
                                         lower_, cancel_)
               : SolveReference(datasets_, chain_, problem_, options_.lm_max_iterations, threads_,
                                k_hat, summary);
  }

  const std::vector<Dataset>& datasets_;
  std::vector<Dataset>* corrected_;
  IntrinsicValues applied_intrinsics_ = IntrinsicValues::Zero();  // SI: raw points are at 0
  const CalibrationOptions& options_;
  int threads_;
  const ProgressCallback& progress_;
  const std::atomic<bool>* cancel_;
  Chain chain_;
  std::vector<std::size_t> free_;
  std::vector<PoseKnots> knots_;
  PairMatcher matcher_;
  MatchProblem problem_;
  std::vector<DatasetPair> fit_pairs_, validation_pairs_;
  RobustLoss loss_;
  SensorMotion motion_;
  std::vector<double> lower_;  // per free parameter (LowerBounds)
};

Icp::Outcome Icp::RunIteration(int iteration, const std::vector<double>& k_hat,
                               const TerminationCriterion& criterion) {
  const auto start = std::chrono::steady_clock::now();
  Outcome outcome;
  Report(iteration, CalibrationStage::kMatching, 0, 0);
  Freeze(k_hat);
  MatchInto(problem_, fit_pairs_, k_hat);  // project, normals, noise/edge filter, match, reject
  matcher_.KeepOnlyNormals();              // until the next Prepare: the solve only reads them
  const std::size_t valid = problem_.MatchCount();
  outcome.stop = criterion.AfterMatching(iteration, valid, UnmatchedFitScans());
  if (outcome.stop) return outcome;

  Report(iteration, CalibrationStage::kSolving, valid, 0);
  IterationReport& report = outcome.report;
  report.iteration = iteration;
  report.matching_seconds = SecondsSince(start);
  report.valid_matches = valid;
  report.noise_fraction = problem_.NoiseFraction();
  outcome.k_hat = k_hat;
  LmSummary summary;
  const bool solved = Solve(outcome.k_hat, summary);
  double delta = 0;
  for (std::size_t i = 0; i < k_hat.size(); ++i)
    delta += (outcome.k_hat[i] - k_hat[i]) * (outcome.k_hat[i] - k_hat[i]);
  delta = std::sqrt(delta);
  // Weighted by the robust loss when it is on (the weights are fixed during the solve).
  const double weight_sum = problem_.WeightSum();
  report.rms_before_m = RmsFromCost(summary.initial_cost, weight_sum, chain_.scale);
  report.rms_after_m = RmsFromCost(summary.final_cost, weight_sum, chain_.scale);
  report.delta = delta;
  report.step =
      options_.step_measure == StepMeasure::kParameters || !solved || !std::isfinite(delta)
          ? delta
          : motion_.Step(k_hat, outcome.k_hat);
  report.lm_iterations = summary.iterations;
  outcome.stop = criterion.AfterSolve(iteration, solved, delta);
  report.seconds = SecondsSince(start);
  return outcome;
}

Rms Icp::Validate(const std::vector<double>& k_hat) {
  Report(0, CalibrationStage::kValidation, 0, 0);
  Freeze(k_hat);
  MatchProblem validation(datasets_, chain_, knots_, free_, threads_, false,
                          options_.cost);  // freed after
  MatchInto(validation, validation_pairs_, k_hat);
  matcher_.ReleaseBaseTrees();  // the held-out registration builds its own
  const Evaluation cost = validation.Evaluate(k_hat);
  Rms rms;
  rms.matches = cost.residuals;
  rms.rms_m = cost.residuals == 0
                  ? 0.0
                  : RmsFromCost(cost.cost, static_cast<double>(cost.residuals), chain_.scale);
  return rms;
}

Icp::SolutionInformation Icp::LinearizePairsAtSolution(const std::vector<double>& k_hat,
                                                       const HeldParameters& held) {
  Freeze(k_hat);
  matcher_.Prepare(k_hat, fit_pairs_);
  // The chain with the held compliance's columns before the latency's, and every free and held
  // intrinsic after them; the free values at the estimate, the held at their assumed values (0).
  // With nothing held it is the fit's own chain, parameters and k_hat.
  Chain chain = chain_;
  const std::size_t K = chain_.ParameterCount(), held_columns = held.elasticity.ElasticityCount();
  if (held_columns > 0) {
    JointCorrection& correction = chain.correction;
    correction.joints = held.elasticity.joints;
    correction.reference_torque = held.elasticity.reference_torque;
    correction.load = held.elasticity.load;
    correction.frozen_parameters.assign(k_hat.begin(), k_hat.begin() + static_cast<long>(K));
    DenormalizeTranslationParameters(correction.frozen_parameters, chain.JointCount(), chain.scale);
  }
  std::vector<double> k(k_hat.begin(), k_hat.begin() + static_cast<long>(K));
  SolutionInformation out;
  std::vector<std::size_t> free;
  std::vector<double> sd;
  auto add = [&](std::size_t index, double value, std::optional<double> held_sd) {
    (held_sd ? out.held : out.estimated).push_back(static_cast<long>(free.size()));
    if (held_sd) sd.push_back(*held_sd);
    free.push_back(index);
    if (index >= k.size()) k.push_back(value);
  };
  for (std::size_t c = 0; c < free_.size() && free_[c] < K; ++c) add(free_[c], 0, std::nullopt);
  const std::size_t elastic = chain_.correction.ElasticityCount();  // held ones only when 0
  for (std::size_t c = 0; c < elastic; ++c) add(K + c, k_hat[K + c], std::nullopt);
  for (std::size_t c = 0; c < held_columns; ++c) add(K + c, 0.0, held.elasticity_sd[c]);
  for (std::size_t l = 0; l < chain_.correction.latency_recordings.size(); ++l)
    add(K + elastic + held_columns + l, k_hat[K + elastic + l], std::nullopt);
  // The intrinsics in their order (scale, offset, focal): free at the estimate, held at 0.
  const SensorIntrinsics& free_intrinsics = chain_.intrinsics;
  const IntrinsicValues values = free_intrinsics.Values(chain_.FreeIntrinsics(k_hat.data()), 1.0);
  const SensorIntrinsics& held_intrinsics = held.intrinsics.which;
  if (!held.intrinsics.Empty()) chain.intrinsics.measure = held_intrinsics.measure;
  chain.intrinsics.scale = free_intrinsics.scale || held_intrinsics.scale;
  chain.intrinsics.offset = free_intrinsics.offset || held_intrinsics.offset;
  chain.intrinsics.focal = free_intrinsics.focal || held_intrinsics.focal;
  const bool is_free[3] = {free_intrinsics.scale, free_intrinsics.offset, free_intrinsics.focal};
  const bool in_chain[3] = {chain.intrinsics.scale, chain.intrinsics.offset,
                            chain.intrinsics.focal};
  for (int t = 0; t < 3; ++t) {
    if (!in_chain[t]) continue;
    const double held_sd = t == 1 ? held.intrinsics.sd[t] / chain_.scale : held.intrinsics.sd[t];
    add(k.size(), values[t], is_free[t] ? std::nullopt : std::optional<double>(held_sd));
  }
  out.held_sd = Eigen::Map<const Eigen::VectorXd>(sd.data(), static_cast<long>(sd.size()));
  // The normal equations of the cost the fit minimized (its loss), one term per pair.
  out.pairs = LinearizeEachPair(datasets_, chain, knots_, matcher_, free, fit_pairs_, k, threads_,
                                options_.cost, loss_);
  matcher_.KeepOnlyNormals();  // the validation's Prepare makes the rest again
  return out;
}

// Per free parameter: its name, whether it is a translation (normalized by s) and the factor from
// its normalized value to SI beyond s: 1, or 1 / reference torque for a joint's compliance
// (theta_hat = compliance * reference torque, joint_correction.h), in rad/Nm.
struct FreeParameters {
  std::vector<std::string> names;
  std::vector<bool> translation;
  std::vector<double> factor;
  std::size_t mcpc = 0;  // the MCPC parameters come first
};

// The latency parameter's name (joint_correction.h): "sensor.latency" for the first recording.
std::string LatencyName(int recording) {
  return recording == 0 ? "sensor.latency" : "recording" + std::to_string(recording) + ".latency";
}

FreeParameters DescribeFree(const RobotModel& nominal, const Icp& icp) {
  FreeParameters out;
  const JointCorrection& correction = icp.chain().correction;
  for (std::size_t index : icp.free()) {
    if (index < nominal.ParameterCount()) {
      out.names.push_back(ParameterName(nominal, index));
      out.translation.push_back(IsTranslationParameter(nominal, index));
      out.factor.push_back(1.0);
      ++out.mcpc;
      continue;
    }
    const std::size_t c = index - nominal.ParameterCount();
    if (c >= correction.Count()) {  // the intrinsics (sensor_intrinsics.h)
      const std::size_t i = c - correction.Count();
      out.names.push_back(icp.chain().intrinsics.Names()[i]);
      out.translation.push_back(icp.chain().intrinsics.Offsets()[i]);
      out.factor.push_back(1.0);
      continue;
    }
    out.translation.push_back(false);
    if (c < correction.ElasticityCount()) {
      out.names.push_back(nominal.joints[correction.joints[c]].name + ".compliance");
      out.factor.push_back(1.0 / correction.reference_torque[c]);
      continue;
    }
    out.names.push_back(
        LatencyName(correction.latency_recordings[c - correction.ElasticityCount()]));
    out.factor.push_back(1.0);  // theta_hat is the latency in s
  }
  return out;
}

Eigen::MatrixXd ScaledBy(const Eigen::MatrixXd& matrix, const std::vector<double>& factor) {
  const Eigen::VectorXd f = Eigen::Map<const Eigen::VectorXd>(factor.data(), matrix.rows());
  return f.asDiagonal() * matrix * f.asDiagonal();
}

// The pairs' normal equations over the parameters `rows` only.
std::vector<PairNormalEquations> Restricted(const std::vector<PairNormalEquations>& pairs,
                                            const std::vector<long>& rows) {
  std::vector<PairNormalEquations> out;
  for (const PairNormalEquations& pair : pairs) {
    const NormalEquations& normal = pair.normal;
    out.push_back(
        {pair.dataset_i,
         pair.dataset_j,
         {normal.hessian(rows, rows), normal.gradient(rows), normal.cost, normal.residuals}});
  }
  return out;
}

// What is held adds to the covariance of the estimated parameters (normalized units; empty when
// nothing is held).
Eigen::MatrixXd HeldCovariance(const Icp::SolutionInformation& solution) {
  if (solution.held.empty()) return {};
  const long size = solution.pairs.front().normal.hessian.rows();
  Eigen::MatrixXd hessian = Eigen::MatrixXd::Zero(size, size);
  for (const PairNormalEquations& pair : solution.pairs) hessian += pair.normal.hessian;
  return ConsiderCovariance(hessian, solution.estimated, solution.held, solution.held_sd);
}

// Standard deviations, covariance, the sensor pose error it predicts and the parameters the scans
// cannot determine, from the normal equations at the solution (covariance.h): the jackknife's,
// plus what the uncertainty of what is held adds. The predicted error and the unobservable
// directions (of the scans alone) are those of the MCPC parameters (their marginal covariance).
void ReportUncertainty(Icp& icp, const RobotModel& nominal, const std::vector<double>& k_hat,
                       double scale, const HeldParameters& held, CalibrationResult& result) {
  const Icp::SolutionInformation solution = icp.LinearizePairsAtSolution(k_hat, held);
  if (solution.pairs.empty()) return;
  std::vector<PairNormalEquations> restricted;  // the jackknife's: the estimated parameters only
  if (!solution.held.empty()) restricted = Restricted(solution.pairs, solution.estimated);
  const std::vector<PairNormalEquations>& pairs =
      solution.held.empty() ? solution.pairs : restricted;
  const long k = static_cast<long>(icp.free().size());
  NormalEquations total{Eigen::MatrixXd::Zero(k, k), Eigen::VectorXd::Zero(k), 0, 0};
  for (const auto& pair : pairs) {
    total.hessian += pair.normal.hessian;
    total.cost += pair.normal.cost;
    total.residuals += pair.normal.residuals;
  }
  const FreeParameters described = DescribeFree(nominal, icp);
  const Observability observability =
      AnalyzeObservability(total.hessian, 2.0 * total.cost, total.residuals, described.names);
  result.poorly_observable = observability.poorly_observable;
  const CovarianceEstimate covariance = EstimateCovariance(pairs);
  const long m = static_cast<long>(described.mcpc);
  const std::vector<std::size_t> mcpc(icp.free().begin(), icp.free().begin() + m);
  result.unobservable =
      UnobservableParameters(total.hessian.topLeftCorner(m, m),
                             covariance.reported.topLeftCorner(m, m), result.model, mcpc, scale);
  result.jackknife_scans = covariance.jackknife_scans;
  const Eigen::MatrixXd held_part = HeldCovariance(solution);
  const auto to_si = [&](const Eigen::MatrixXd& normalized) {
    return ScaledBy(ToSiUnits(normalized, described.translation, scale), described.factor);
  };
  result.covariance_of_scans = to_si(covariance.reported);
  result.covariance =
      held_part.size() > 0 ? to_si(covariance.reported + held_part) : result.covariance_of_scans;
  if (held_part.size() > 0) {
    result.predicted_held =
        PredictPoseError(result.model, mcpc, to_si(held_part).topLeftCorner(m, m),
                         kPredictionSamples, kPredictionSeed);
  }
  const Eigen::MatrixXd naive = to_si(covariance.naive);
  result.predicted = PredictPoseError(result.model, mcpc, result.covariance.topLeftCorner(m, m),
                                      kPredictionSamples, kPredictionSeed);
  result.predicted_naive = PredictPoseError(result.model, mcpc, naive.topLeftCorner(m, m),
                                            kPredictionSamples, kPredictionSeed);
  const std::vector<double> k_init = ToParameterVector(nominal);
  for (std::size_t c = 0; c < icp.free().size(); ++c) {
    const std::size_t index = icp.free()[c];
    ParameterReport parameter;
    parameter.name = described.names[c];
    parameter.nominal = index < k_init.size() ? k_init[index] : 0.0;
    parameter.calibrated = k_hat[index] * described.factor[c];
    if (described.translation[c]) parameter.calibrated *= scale;
    const JointCorrection& correction = icp.chain().correction;
    if (index >= k_init.size() && index - k_init.size() < correction.Count()) {
      const std::size_t column = index - k_init.size();
      if (column >= correction.ElasticityCount())  // the latency starts at its recording's
        parameter.nominal = correction.latency_start_s[column - correction.ElasticityCount()];
      else if (!nominal.compliance.empty())
        parameter.nominal = nominal.compliance[correction.joints[column]];
    }
    const long i = static_cast<long>(c);
    parameter.std_dev = std::sqrt(std::max(result.covariance(i, i), 0.0));
    parameter.naive_std_dev =
        observability.std_dev[c] * (described.translation[c] ? scale : 1.0) * described.factor[c];
    result.parameters.push_back(parameter);
  }
}

// The calibrated model of `k_hat`: its MCPC parameters and, with a joint correction, the
// compliance of every joint (0 for the joints kept rigid).
void SetCalibratedModel(const Icp& icp, const std::vector<double>& k_hat, double scale,
                        RobotModel& model) {
  const std::size_t K = icp.chain().ParameterCount();
  std::vector<double> k_final(k_hat.begin(), k_hat.begin() + static_cast<long>(K));
  DenormalizeTranslationParameters(k_final, model.JointCount(), scale);
  FromParameterVector(k_final, model);
  const JointCorrection& correction = icp.chain().correction;
  if (correction.ElasticityCount() == 0) return;  // the latency is no part of the model
  model.compliance.assign(model.JointCount(), 0.0);
  for (std::size_t c = 0; c < correction.ElasticityCount(); ++c)
    model.compliance[correction.joints[c]] = k_hat[K + c] / correction.reference_torque[c];
}

// After the loop: the calibrated model, its uncertainty and validation, and whether it is usable.
void Finalize(Icp& icp, const RobotModel& nominal, const std::vector<double>& k_hat, double scale,
              const HeldParameters& held, CalibrationResult& result) {
  const bool fitted = !result.iterations.empty();
  SetCalibratedModel(icp, k_hat, scale, result.model);
  icp.ReleaseFitMatches();
  if (fitted && result.termination != Termination::kCancelled) {
    icp.Report(static_cast<int>(result.iterations.size()), CalibrationStage::kCovariance, 0, 0);
    ReportUncertainty(icp, nominal, k_hat, scale, held, result);
    if (result.validation_scans > 0) {
      const Rms after = icp.Validate(k_hat);
      result.validation.matches_after = after.matches;
      result.validation.rms_after_m = after.rms_m;
      result.held_out = icp.RegisterHeldOut();
    }
  }
  bool finite = true;
  for (double value : k_hat) finite &= std::isfinite(value);
  const bool terminated_well = result.termination == Termination::kConverged ||
                               result.termination == Termination::kMaxIterations;
  // Whether the validation scans agree is the acceptance gate's question (daemon/gate.h), with
  // a tolerance for the noise of the comparison: a recalibration of a correct model may end a
  // hair above its validation RMS.
  result.usable = fitted && finite && terminated_well;
  if (!result.usable && !fitted) result.model = nominal;
  // What changed against the start model, judged against the covariance (model_change.h).
  if (fitted && finite && result.termination != Termination::kCancelled) {
    // Judged against the scans' own covariance: what the calibration holds (the sensor's
    // intrinsics) errs alike in the session that made the start model with the same sensor.
    result.change =
        DescribeModelChange(nominal, result.model, result.covariance_of_scans, icp.free());
    result.change_known = true;
  }
}

// Joint elasticity's correction (joint_correction.h) from the fit scans' poses (at most 64 per
// scan), or why there is none.
std::string ElasticityFor(const std::vector<Dataset>& datasets, const RobotModel& nominal,
                          JointCorrection& correction) {
  if (!nominal.gravity.Present())
    return "elasticity needs the link masses of the robot model (its gravity: block)";
  std::vector<double> joints;  // configuration-major
  for (const Dataset& dataset : datasets) {
    if (dataset.validation) continue;
    const std::size_t poses = dataset.PoseCount();
    const std::size_t step = std::max<std::size_t>(1, poses / 64);
    double buffer[kMaxJoints];
    for (std::size_t pose = 0; pose < poses; pose += step) {
      const double* q = dataset.JointsOfPose(pose, buffer);
      joints.insert(joints.end(), q, q + dataset.joint_count);
    }
  }
  std::vector<const double*> configurations;
  for (std::size_t at = 0; at < joints.size(); at += nominal.JointCount())
    configurations.push_back(joints.data() + at);
  correction = ElasticityCorrection(nominal, configurations);
  if (correction.Empty()) return "elasticity: no joint has a gravity torque in the fit scans";
  return {};
}

// Without --elasticity, a robot model with a compliance (a calibration's with it) keeps it, held
// (joint_correction.h, held_compliance).
std::string ComplianceHeldFor(const RobotModel& nominal, const CalibrationOptions& options,
                              JointCorrection& correction) {
  if (!nominal.gravity.Present())
    return "the robot model's compliance needs its link masses (its gravity: block)";
  if (options.solver == SolverKind::kReference) {
    return "the robot model has a compliance, which the reference solver cannot apply (it runs "
           "the rigid chain): use solver fast";
  }
  correction = HeldCompliance(nominal);
  return {};
}

// RMS joint speed [rad/s or m/s, the norm over the joints] of a scan with joint timing, over at
// most 64 of its poses.
double RmsJointSpeed(const Dataset& dataset) {
  const std::size_t poses = dataset.PoseCount();
  const std::size_t step = std::max<std::size_t>(1, poses / 64);
  std::vector<double> velocity(dataset.joint_count);
  double sum = 0;
  std::size_t count = 0;
  for (std::size_t pose = 0; pose < poses; pose += step, ++count) {
    JointVelocitiesAt(*dataset.joint_states,
                      dataset.PoseUtime(pose) + 1e6 * dataset.joint_latency_s,
                      kVelocityHalfWindowUs, velocity);
    for (double v : velocity) sum += v * v;
  }
  return std::sqrt(sum / static_cast<double>(std::max<std::size_t>(count, 1)));
}

// The sensor latency's columns (joint_correction.h): one per recording whose fit scans carry
// joint timing and move. A recording scanned at rest (every fit scan's RMS joint speed below
// kMinLatencySpeed, a depth camera's stationary views) keeps its start latency and is named in
// `at_rest`: the scans cannot show it. Returns why the latency cannot be estimated at all.
std::string LatencyFor(const std::vector<Dataset>& datasets, JointCorrection& correction,
                       std::vector<std::string>& at_rest) {
  JointCorrection candidates;
  if (AddLatencyColumns(datasets, candidates) == 0)
    return "latency: no fit scan has its measurement times and joint states "
           "(RecordingOptions::joint_timing)";
  for (std::size_t l = 0; l < candidates.latency_recordings.size(); ++l) {
    const int recording = candidates.latency_recordings[l];
    double fastest = 0;  // rad/s (or m/s): the largest RMS joint speed of a fit scan
    for (const Dataset& dataset : datasets) {
      if (dataset.validation || dataset.recording != recording || !dataset.HasJointTiming())
        continue;
      fastest = std::max(fastest, RmsJointSpeed(dataset));
    }
    if (fastest >= kMinLatencySpeed) {
      correction.latency_recordings.push_back(recording);
      correction.latency_start_s.push_back(candidates.latency_start_s[l]);
      continue;
    }
    char text[200];
    std::snprintf(text, sizeof text,
                  "%s: not observable, the fit scans were taken at rest (RMS joint speed at "
                  "most %.2g rad/s): kept at %.6g s",
                  LatencyName(recording).c_str(), fastest, candidates.latency_start_s[l]);
    at_rest.push_back(text);
  }
  if (correction.Count() > kMaxCorrectionColumns)
    return "latency: more than " + std::to_string(kMaxCorrectionColumns) + " extra parameters";
  return {};
}

// True when `nominal`'s mask frees every length of the arm beyond its base (each non-zero
// translation of the segments and the tool) and no joint is prismatic: then scaling all of them
// and the sensor's measure by one factor about the first joint leaves every residual unchanged,
// and the measure's scale is not observable (sensor_intrinsics.h).
bool ScaleIsGauge(const RobotModel& nominal) {
  const std::vector<double> k = ToParameterVector(nominal);
  for (std::size_t i = kFullTransformParamCount; i < k.size(); ++i) {
    if (IsTranslationParameter(nominal, i) && k[i] != 0.0 && !nominal.mask[i]) return false;
  }
  for (const JointType type : JointTypes(nominal)) {
    if (type == JointType::kPrismatic) return false;  // its measured travel is a length
  }
  return true;
}

// The intrinsics of the options for the datasets' sensor, or why there are none: every scan
// must measure the same way (one sensor), a focal length needs a depth measure, and a free scale
// a fixed length of the arm (with `automatic`: taken only then).
std::string IntrinsicsFor(const std::vector<Dataset>& datasets, const RobotModel& nominal,
                          const CalibrationOptions& options, SensorIntrinsics& intrinsics) {
  intrinsics.measure = MeasureKindOf(datasets.front().layout);
  for (const Dataset& dataset : datasets) {
    if (MeasureKindOf(dataset.layout) != intrinsics.measure)
      return "intrinsics: scan " + std::to_string(dataset.scan_index) +
             " comes from another kind of sensor (one sensor's intrinsics are calibrated)";
  }
  const bool depth = intrinsics.measure == MeasureKind::kDepth;
  const bool gauge = ScaleIsGauge(nominal);
  const IntrinsicsChoice& chosen = options.intrinsics;
  intrinsics.offset = chosen.offset || chosen.automatic;
  intrinsics.focal = chosen.focal || (chosen.automatic && depth);
  intrinsics.scale = chosen.scale || (chosen.automatic && !gauge);
  if (intrinsics.focal && !depth)
    return "intrinsics: a LiDAR has no focal length (its rays are angles; calibrate its range)";
  if (intrinsics.scale && gauge) {
    return "intrinsics: " + intrinsics.Names().front() +
           " is not observable with this mask: scaling every calibrated length of the arm and "
           "the measure by one factor leaves every residual unchanged; keep a length fixed (the "
           "robot file's calibrate: block) or calibrate in remaster mode, or free only the offset "
           "and the focal length";
  }
  return {};
}

// What the calibration holds although it is uncertain (deviation 21): the intrinsics the options
// give an uncertainty that are not free (a LiDAR has no focal length; none when the scans come
// from different kinds of sensor), and the compliance of a rigid model whose robot file gives
// its uncertainty, where elasticity is not calibrated.
HeldParameters HeldFor(const std::vector<Dataset>& datasets, const RobotModel& nominal,
                       const CalibrationOptions& options, const SensorIntrinsics& free) {
  HeldParameters held;
  const MeasureKind measure = MeasureKindOf(datasets.front().layout);
  bool one_kind = true;
  for (const Dataset& dataset : datasets) one_kind &= MeasureKindOf(dataset.layout) == measure;
  const IntrinsicValues sd(options.intrinsic_scale_sd, options.intrinsic_offset_sd_m,
                           options.intrinsic_focal_sd);
  held.intrinsics = HeldIntrinsicsFor(measure, one_kind ? sd : IntrinsicValues::Zero(), free);
  const std::vector<double>& compliance_sd = nominal.gravity.compliance_sd;
  if (options.elasticity || HasCompliance(nominal) || compliance_sd.empty() ||
      !ElasticityFor(datasets, nominal, held.elasticity).empty())
    return held;
  for (std::size_t c = 0; c < held.elasticity.ElasticityCount(); ++c) {
    held.elasticity_sd.push_back(compliance_sd[held.elasticity.joints[c]] *
                                 held.elasticity.reference_torque[c]);
  }
  return held;
}

// k_hat at the start: normalize(k_init), then the joint correction's start (a compliance of the
// model file or rigid, each latency's start value), then the intrinsics at 0 (the sensor file's).
std::vector<double> StartParameters(const RobotModel& nominal, double scale,
                                    const JointCorrection& correction,
                                    const SensorIntrinsics& intrinsics) {
  std::vector<double> k_hat = ToParameterVector(nominal);
  NormalizeTranslationParameters(k_hat, nominal.JointCount(), scale);
  for (std::size_t c = 0; c < correction.ElasticityCount(); ++c) {
    const double compliance =
        nominal.compliance.empty() ? 0.0 : nominal.compliance[correction.joints[c]];
    k_hat.push_back(compliance * correction.reference_torque[c]);
  }
  for (double start : correction.latency_start_s) k_hat.push_back(start);
  k_hat.resize(k_hat.size() + intrinsics.Count(), 0.0);
  return k_hat;
}

// repeat ... until |delta k_opt| <= epsilon (Algorithm 1), bounded by i_max; the step measured
// and the iteration accelerated as the options say (deviation 18), coarse to fine when asked
// (deviation 24: converged at a coarse stride, the loop goes on at half of it; the acceleration
// restarts, its past steps matched other points). Leaves the result in k_hat.
Stop RunLoop(Icp& icp, const CalibrationOptions& options, const TerminationCriterion& criterion,
             std::vector<double>& k_hat, CalibrationResult& result) {
  auto accelerate = [&] {
    return AndersonAcceleration(options.acceleration, icp.free(), icp.motion().Metric(k_hat),
                                icp.lower());
  };
  AndersonAcceleration acceleration = accelerate();
  int stride = std::max(options.coarse_stride, options.query_stride);
  icp.SetQueryStride(stride);
  std::optional<Stop> stop;
  for (int iteration = 1;; ++iteration) {
    if ((stop = criterion.BeforeIteration(iteration))) break;
    Icp::Outcome outcome = icp.RunIteration(iteration, k_hat, criterion);
    if ((stop = std::move(outcome.stop))) break;  // the step is not kept
    const IterationReport& report = result.iterations.emplace_back(outcome.report);
    icp.Report(iteration, CalibrationStage::kIterationDone, report.valid_matches, report.step);
    const std::vector<double> x = std::exchange(k_hat, std::move(outcome.k_hat));
    if ((stop = criterion.AfterStep(iteration, report.step))) {
      if (stride == options.query_stride) break;
      stride = std::max(stride / 2, options.query_stride);
      icp.SetQueryStride(stride);
      result.accelerated += acceleration.accelerated();
      result.acceleration_dropped += acceleration.rejected();
      acceleration = accelerate();
      stop.reset();
      continue;
    }
    k_hat = acceleration.Next(x, std::move(k_hat), report.step, report.valid_matches);
  }
  k_hat = acceleration.Settled(std::move(k_hat));
  icp.SetQueryStride(options.query_stride);  // the validation and the covariance match as without
  result.step_measure = options.step_measure;
  result.accelerated += acceleration.accelerated();
  result.acceleration_dropped += acceleration.rejected();
  return *stop;
}

// Calibrate() on `datasets`; `writable` is the same vector when the caller gives it up (the
// engine then corrects its points in place), else null (a copy is corrected).
CalibrationResult CalibrateDatasets(const std::vector<Dataset>& datasets,
                                    std::vector<Dataset>* writable, const RobotModel& nominal,
                                    const CalibrationOptions& options,
                                    const ProgressCallback& progress,
                                    const std::atomic<bool>* cancel) {
  const auto start = std::chrono::steady_clock::now();
  CalibrationResult result;
  result.model = nominal;
  result.search = options.search;
  result.solver = options.solver;
  result.threads = options.threads > 0 ? options.threads : DefaultThreadCount();
  auto fail = [&](std::string message) {
    result.termination = Termination::kInvalidInput;
    result.message = std::move(message);
    result.runtime_s = SecondsSince(start);
    return result;
  };
  // Bad data is a result, never a crash.
  std::string problem;
  if (!options.IsValid(&problem)) return fail("options: " + problem);
  if (problem = CheckInput(datasets, nominal, result); !problem.empty()) return fail(problem);

  // normalizeTranslation(k_init): s from the first fit dataset projected with k_init.
  const double scale = EngineScale(datasets, nominal);
  if (!(scale > 0)) {
    std::size_t first_fit = 0;
    while (datasets[first_fit].validation) ++first_fit;
    return fail("scan " + std::to_string(datasets[first_fit].scan_index) +
                ": cannot compute the scale s");
  }
  result.scale_m = scale;
  JointCorrection correction;
  if (options.elasticity) {
    if (problem = ElasticityFor(datasets, nominal, correction); !problem.empty())
      return fail(problem);
  } else if (HasCompliance(nominal)) {
    if (problem = ComplianceHeldFor(nominal, options, correction); !problem.empty())
      return fail(problem);
  }
  std::vector<std::string> at_rest;  // recordings whose latency the scans cannot show
  if (options.estimate_latency) {
    if (problem = LatencyFor(datasets, correction, at_rest); !problem.empty()) return fail(problem);
  }
  SensorIntrinsics intrinsics;
  std::vector<Dataset> copy;
  std::vector<Dataset>* corrected = nullptr;  // with intrinsics: the points kept corrected
  if (options.AnyIntrinsic()) {
    if (problem = IntrinsicsFor(datasets, nominal, options, intrinsics); !problem.empty())
      return fail(problem);
    if (writable == nullptr) copy = datasets;
    corrected = writable != nullptr ? writable : &copy;
  }
  std::vector<double> k_hat = StartParameters(nominal, scale, correction, intrinsics);

  Icp icp(corrected != nullptr ? *corrected : datasets, corrected, nominal, options, scale,
          std::move(correction), intrinsics, result.threads, progress, cancel);
  if (result.validation_scans > 0) {
    const Rms before = icp.Validate(k_hat);
    result.validation.available = true;
    result.validation.matches_before = before.matches;
    result.validation.rms_before_m = before.rms_m;
  }
  const Stop stop = RunLoop(icp, options, TerminationCriterion(options, cancel), k_hat, result);
  result.termination = stop.termination;
  result.message = stop.message;
  result.converged = stop.termination == Termination::kConverged;
  result.points_on_links = icp.PointsOnLinks();
  Finalize(icp, nominal, k_hat, scale, HeldFor(datasets, nominal, options, intrinsics), result);
  result.poorly_observable.insert(result.poorly_observable.end(), at_rest.begin(), at_rest.end());
  result.runtime_s = SecondsSince(start);
  return result;
}

}  // namespace

CalibrationResult Calibrate(const std::vector<Dataset>& datasets, const RobotModel& nominal,
                            const CalibrationOptions& options, const ProgressCallback& progress,
                            const std::atomic<bool>* cancel) {
  return CalibrateDatasets(datasets, nullptr, nominal, options, progress, cancel);
}

CalibrationResult Calibrate(std::vector<Dataset>&& datasets, const RobotModel& nominal,
                            const CalibrationOptions& options, const ProgressCallback& progress,
                            const std::atomic<bool>* cancel) {
  return CalibrateDatasets(datasets, &datasets, nominal, options, progress, cancel);
}

}  // namespace selfcal::calib
