#include "core/calib/calibrate.h"

#include <chrono>
#include <cmath>

#include "core/calib/chain.h"
#include "core/calib/normalization.h"
#include "core/calib/observability.h"
#include "core/calib/pair_matching.h"
#include "core/calib/parallel.h"
#include "core/calib/point_to_plane.h"
#include "core/calib/reference_solver.h"
#include "core/model/kinematics.h"

namespace selfcal::calib {

const char* SolverName(SolverKind kind) { return kind == SolverKind::kFast ? "fast" : "reference"; }

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

namespace {

constexpr std::size_t kMaxJoints = 16;

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
    if (dataset.pose_joints.size() != dataset.PoseCount() * dataset.joint_count) {
      return scan + ": " + std::to_string(dataset.pose_joints.size()) + " joint values for " +
             std::to_string(dataset.PoseCount()) + " poses";
    }
    for (double value : dataset.pose_joints) {
      if (!std::isfinite(value)) return scan + ": joint positions contain NaN or infinity";
    }
    if (dataset.ValidPointCount() == 0) return scan + ": no valid points";
  }
  return {};
}

struct Rms {
  std::size_t matches = 0;
  double rms_m = 0;
};

Rms RmsOf(const MatchProblem& problem, const std::vector<double>& k_hat, double scale) {
  const NormalEquations e = problem.Evaluate(k_hat, false);
  Rms rms;
  rms.matches = e.residuals;
  rms.rms_m =
      e.residuals == 0 ? 0.0 : std::sqrt(2.0 * e.cost / static_cast<double>(e.residuals)) * scale;
  return rms;
}

}  // namespace

CalibrationResult Calibrate(const std::vector<Dataset>& datasets, const RobotModel& nominal,
                            const CalibrationOptions& options, const ProgressCallback& progress,
                            const std::atomic<bool>* cancel) {
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&start] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  CalibrationResult result;
  result.model = nominal;
  result.solver = options.solver;
  result.threads = options.threads > 0 ? options.threads : DefaultThreadCount();
  const int threads = result.threads;
  auto fail = [&](Termination termination, std::string message) {
    result.termination = termination;
    result.message = std::move(message);
    result.runtime_s = elapsed();
    return result;
  };
  auto report = [&](int iteration, const char* stage, std::size_t matches, double delta) {
    if (progress) progress({iteration, options.i_max, stage, matches, delta});
  };

  // --- Input checks: bad data is a result, never a crash ----------------------------------------
  if (const std::string problem = CheckConsistency(nominal); !problem.empty()) {
    return fail(Termination::kInvalidInput, "robot model: " + problem);
  }
  if (nominal.JointCount() > kMaxJoints) {
    return fail(Termination::kInvalidInput, "robot model has more than 16 joints");
  }
  if (const std::string problem = CheckDatasets(datasets, nominal); !problem.empty()) {
    return fail(Termination::kInvalidInput, problem);
  }
  std::vector<bool> is_fit(datasets.size()), is_validation(datasets.size());
  for (std::size_t d = 0; d < datasets.size(); ++d) {
    is_fit[d] = !datasets[d].validation;
    is_validation[d] = datasets[d].validation;
    result.fit_scans += is_fit[d] ? 1 : 0;
    result.validation_scans += is_validation[d] ? 1 : 0;
    result.points += datasets[d].PointCount();
  }
  if (result.fit_scans < 2) {
    return fail(Termination::kInvalidInput,
                "need at least two fit scans, got " + std::to_string(result.fit_scans));
  }
  std::vector<std::size_t> free;
  for (std::size_t i = 0; i < nominal.mask.size(); ++i) {
    if (nominal.mask[i]) free.push_back(i);
  }
  if (free.empty())
    return fail(Termination::kInvalidInput, "the mask selects no parameter to calibrate");

  // --- Normalization: s from the first fit dataset projected with k_init -------------------------
  const std::vector<double> k_init = ToParameterVector(nominal);
  const std::vector<JointType> joint_types = JointTypes(nominal);
  std::size_t first_fit = 0;
  while (!is_fit[first_fit]) ++first_fit;
  const double scale = ComputeScale(datasets[first_fit], joint_types, k_init);
  if (!(scale > 0) || !std::isfinite(scale)) {
    return fail(
        Termination::kInvalidInput,
        "scan " + std::to_string(datasets[first_fit].scan_index) + ": cannot compute the scale s");
  }
  result.scale_m = scale;
  Chain chain{joint_types, scale, false};
  for (JointType type : joint_types) chain.has_prismatic |= type == JointType::kPrismatic;
  std::vector<double> k_hat = NormalizeParameters(nominal, k_init, scale);

  // Knots of every dataset's poses (pose_knots.h): built once, shared by both solvers' helpers.
  std::vector<PoseKnots> knots(datasets.size());
  ParallelFor(datasets.size(), threads,
              [&](std::size_t d) { knots[d] = BuildPoseKnots(datasets[d]); });
  const bool keep_all_matches = options.solver == SolverKind::kReference;
  PairMatcher matcher(datasets, chain, knots, options, threads);
  MatchProblem problem(datasets, chain, knots, free, threads, keep_all_matches);
  const std::vector<DatasetPair> fit_pairs = AllPairs(is_fit);
  const std::vector<DatasetPair> validation_pairs = PairsTouching(is_validation);
  // Projection, normals and filter at `parameters`, then matching and rejection into `target`.
  auto match_into = [&](MatchProblem& target, const std::vector<DatasetPair>& pairs,
                        const std::vector<double>& parameters) {
    matcher.Prepare(parameters);
    target.SetMatches(
        pairs, [&](std::size_t p) { return matcher.MatchPair(pairs[p]); }, matcher.clouds(),
        parameters);
  };
  auto validate = [&](const std::vector<double>& parameters) {
    report(0, "validation", 0, 0);
    MatchProblem validation_problem(datasets, chain, knots, free, threads, false);  // freed after
    match_into(validation_problem, validation_pairs, parameters);
    return RmsOf(validation_problem, parameters, scale);
  };
  if (result.validation_scans > 0) {
    const Rms before = validate(k_hat);
    result.validation.available = true;
    result.validation.matches_before = before.matches;
    result.validation.rms_before_m = before.rms_m;
  }

  // --- Algorithm 1 ------------------------------------------------------------------------------
  bool stopped = false;
  for (int iteration = 1; iteration <= options.i_max && !stopped; ++iteration) {
    const auto iteration_start = std::chrono::steady_clock::now();
    if (cancel != nullptr && cancel->load()) {
      result.termination = Termination::kCancelled;
      result.message = "cancelled before iteration " + std::to_string(iteration);
      stopped = true;
      break;
    }
    report(iteration, "matching", 0, 0);
    match_into(problem, fit_pairs, k_hat);  // project, normals, noise/edge filter, match, reject
    const std::size_t valid = problem.MatchCount();
    if (valid < options.min_matches) {
      std::string lonely;
      for (std::size_t d = 0; d < datasets.size(); ++d) {
        if (is_fit[d] && problem.MatchesPerDataset()[d] == 0)
          lonely += " " + std::to_string(datasets[d].scan_index);
      }
      result.termination = Termination::kTooFewMatches;
      result.message = "iteration " + std::to_string(iteration) + ": " + std::to_string(valid) +
                       " valid matches, fewer than " + std::to_string(options.min_matches) +
                       (lonely.empty() ? std::string() : "; scans without any overlap:" + lonely);
      stopped = true;
      break;
    }
    if (cancel != nullptr && cancel->load()) {  // matching can take seconds: look again
      result.termination = Termination::kCancelled;
      result.message = "cancelled during iteration " + std::to_string(iteration);
      stopped = true;
      break;
    }
    report(iteration, "solving", valid, 0);
    IterationReport iteration_report;
    iteration_report.iteration = iteration;
    iteration_report.matching_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - iteration_start).count();
    iteration_report.valid_matches = valid;
    std::vector<double> k_new = k_hat;
    LmSummary summary;
    const bool ok =
        options.solver == SolverKind::kFast
            ? SolveLevenbergMarquardt(problem, options.lm_max_iterations, k_new, summary, cancel)
            : SolveReference(datasets, chain, problem, options.lm_max_iterations, threads, k_new,
                             summary);
    if (cancel != nullptr && cancel->load()) {  // the solve was cut short: its step is not kept
      result.termination = Termination::kCancelled;
      result.message = "cancelled during iteration " + std::to_string(iteration);
      stopped = true;
      break;
    }
    double delta = 0;
    for (std::size_t i = 0; i < k_new.size(); ++i)
      delta += (k_new[i] - k_hat[i]) * (k_new[i] - k_hat[i]);
    delta = std::sqrt(delta);
    const auto rms = [&](double cost) {
      return std::sqrt(2.0 * cost / static_cast<double>(valid)) * scale;
    };
    iteration_report.rms_before_m = rms(summary.initial_cost);
    iteration_report.rms_after_m = rms(summary.final_cost);
    iteration_report.delta = delta;
    iteration_report.lm_iterations = summary.iterations;
    if (!ok || !std::isfinite(delta)) {
      result.termination = Termination::kSolverFailed;
      result.message =
          "iteration " + std::to_string(iteration) + ": the solver produced non-finite values";
      stopped = true;
      break;
    }
    k_hat = k_new;
    iteration_report.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - iteration_start).count();
    result.iterations.push_back(iteration_report);
    report(iteration, "iteration done", valid, delta);
    if (delta <= options.epsilon) {
      result.termination = Termination::kConverged;
      result.converged = true;
      result.message = "|delta k| = " + std::to_string(delta) + " <= epsilon after " +
                       std::to_string(iteration) + " iterations";
      stopped = true;
    }
  }
  if (!stopped) {
    result.termination = Termination::kMaxIterations;
    result.message =
        "not converged: i_max = " + std::to_string(options.i_max) + " iterations reached";
  }

  const bool fitted = !result.iterations.empty();
  const std::vector<double> k_final = DenormalizeParameters(nominal, k_hat, scale);
  FromParameterVector(k_final, result.model);

  // --- Uncertainty and observability at the solution --------------------------------------------
  if (fitted && result.termination != Termination::kCancelled) {
    report(static_cast<int>(result.iterations.size()), "covariance", 0, 0);
    match_into(problem, fit_pairs, k_hat);
    const NormalEquations normal = problem.Evaluate(k_hat, true);
    problem.Clear();
    std::vector<std::string> names;
    for (std::size_t index : free) names.push_back(ParameterName(nominal, index));
    const Observability observability =
        AnalyzeObservability(normal.hessian, 2.0 * normal.cost, normal.residuals, names);
    result.poorly_observable = observability.poorly_observable;
    for (std::size_t c = 0; c < free.size(); ++c) {
      const std::size_t index = free[c];
      ParameterReport parameter;
      parameter.name = names[c];
      parameter.nominal = k_init[index];
      parameter.calibrated = k_final[index];
      parameter.std_dev =
          observability.std_dev[c] * (IsTranslationParameter(nominal, index) ? scale : 1.0);
      result.parameters.push_back(parameter);
    }
    if (result.validation_scans > 0) {
      const Rms after = validate(k_hat);
      result.validation.matches_after = after.matches;
      result.validation.rms_after_m = after.rms_m;
    }
  }

  bool finite = true;
  for (double value : k_final) finite &= std::isfinite(value);
  const bool terminated_well = result.termination == Termination::kConverged ||
                               result.termination == Termination::kMaxIterations;
  const bool validation_ok = !result.validation.available ||
                             (result.validation.matches_after > 0 &&
                              result.validation.rms_after_m <= result.validation.rms_before_m);
  result.usable = fitted && finite && terminated_well && validation_ok;
  if (fitted && terminated_well && !validation_ok) {
    result.message += "; rejected: validation RMS did not improve";
  }
  if (!result.usable && !fitted) result.model = nominal;
  result.runtime_s = elapsed();
  return result;
}

}  // namespace selfcal::calib
