#include "core/plan/information_planner.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>

#include "core/calib/covariance.h"
#include "core/model/evaluation.h"

namespace selfcal::plan {
namespace {

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void Say(const PlanProgress& progress, const std::string& line) {
  if (progress) progress(line);
}

// sigma of one match: both ends' noise, RMS over the sighted views' points (the sensor's
// sigma_abs + sigma_rel * its measure: the range of a LiDAR, the depth of the others).
double MatchSigma(const sim::SensorModel& sensor, const std::vector<calib::Dataset>& datasets) {
  const bool lidar = sensor.kind == SensorLayout::kRotatingLidar;
  double sum = 0;
  std::size_t count = 0;
  for (const calib::Dataset& dataset : datasets) {
    for (std::size_t i = 0; i < dataset.PointCount(); ++i) {
      if (!dataset.IsValid(i)) continue;
      const double measure =
          lidar ? std::hypot(dataset.x[i], dataset.y[i], dataset.z[i]) : dataset.z[i];
      const double sigma = sensor.Sigma(measure);
      sum += sigma * sigma;
      ++count;
    }
  }
  return count > 0 ? std::sqrt(2.0 * sum / static_cast<double>(count)) : 0.0;
}

// Per free parameter of `free`, the factor from normalized to SI (s for translations).
Eigen::VectorXd ToSi(const RobotModel& model, const std::vector<std::size_t>& free, double scale) {
  Eigen::VectorXd d(static_cast<long>(free.size()));
  for (std::size_t c = 0; c < free.size(); ++c)
    d[static_cast<long>(c)] = IsTranslationParameter(model, free[c]) ? scale : 1.0;
  return d;
}

// What the calibration will hold at the sensor file's values although they are uncertain
// (docs/engine.md, deviation 21): the intrinsics with an uncertainty the options do not free
// (with `automatic` the offset and a camera's focal length are freed, the scale held).
calib::HeldIntrinsics HeldByTheCalibration(const sim::SensorModel& sensor,
                                           const calib::CalibrationOptions& engine) {
  calib::SensorIntrinsics free;
  free.scale = engine.intrinsics.scale;
  free.offset = engine.intrinsics.offset || engine.intrinsics.automatic;
  free.focal = engine.intrinsics.focal || engine.intrinsics.automatic;
  const calib::MeasureKind measure = sensor.kind == SensorLayout::kRotatingLidar
                                         ? calib::MeasureKind::kRange
                                         : calib::MeasureKind::kDepth;
  return calib::HeldIntrinsicsFor(
      measure, {engine.intrinsic_scale_sd, engine.intrinsic_offset_sd_m, engine.intrinsic_focal_sd},
      free);
}

// Masks what all candidates together cannot determine (the naive covariance of their pairs).
void MaskUnobservable(CandidateSet& set) {
  const auto& information = set.information;
  const std::size_t estimated = information.EstimatedCount();
  const long k = static_cast<long>(estimated);
  Eigen::MatrixXd total = Eigen::MatrixXd::Zero(k, k);
  for (const auto& pair : information.pairs) total += pair.normal.hessian.topLeftCorner(k, k);
  total *= set.information_factor;
  const Eigen::MatrixXd naive = set.sigma_m * set.sigma_m /
                                (information.scale_m * information.scale_m) *
                                calib::PseudoInverse(total);
  std::vector<bool> masked(estimated, false);
  const std::vector<std::size_t> free(information.free.begin(),
                                      information.free.begin() + static_cast<long>(estimated));
  for (const auto& finding :
       calib::FindUnobservable(total, naive, set.nominal, free, information.scale_m)) {
    set.unobservable.push_back(finding.text);
    for (std::size_t c : finding.parameters) masked[c] = true;
  }
  for (std::size_t c = 0; c < estimated; ++c) {
    if (masked[c]) {
      set.masked.push_back(ParameterName(set.nominal, information.free[c]));
      set.nominal.mask[information.free[c]] = false;
    } else {
      set.selection_free.push_back(c);
    }
  }
}

}  // namespace

bool PlannerOptions::IsValid(std::string* error) const {
  auto fail = [&](const std::string& text) {
    if (error != nullptr) *error = text;
    return false;
  };
  if (max_scans < 2) return fail("max_scans = " + std::to_string(max_scans) + ", must be >= 2");
  if (min_scans < 2 || min_scans > max_scans)
    return fail("min_scans = " + std::to_string(min_scans) + ", must be in [2, max_scans]");
  if (!(target_m >= 0) || !std::isfinite(target_m)) return fail("target must be >= 0");
  if (candidates != 0 && candidates < max_scans)
    return fail("candidates = " + std::to_string(candidates) + ", must be 0 or >= max_scans");
  if (planning_cells < 100) return fail("planning_cells must be >= 100");
  if (!(min_coverage >= 0 && min_coverage < 1)) return fail("min_coverage must be in [0, 1)");
  if (!(prior_m > 0 && prior_rad > 0)) return fail("the prior must be positive");
  if (!(link_radius >= 0)) return fail("link_radius must be >= 0");
  if (threads < 0) return fail("threads must be >= 0");
  return true;
}

Expected<CandidateSet> MakeCandidates(const RobotModel& nominal, const sim::SensorModel& sensor,
                                      const sim::Scene& scene, const sim::PlanOptions& generator,
                                      const calib::CalibrationOptions& engine,
                                      const PlannerOptions& options, const PlanProgress& progress) {
  const auto start = std::chrono::steady_clock::now();
  if (std::string problem; !options.IsValid(&problem)) return Error{"planner: " + problem};
  CandidateSet set;
  set.nominal = nominal;
  sim::PlanOptions views = generator;
  // Candidates in the generator's order (the paper-style plan of N is the first N); the planner
  // checks their links itself (`colliding`) and orders what it chose.
  views.link_radius = 0;
  views.fit_scans = options.candidates > 0 ? options.candidates : 3 * options.max_scans;
  auto generated = sim::MakeScanPlan(nominal, sensor, scene, views);
  if (!generated) return generated.error();
  for (auto& scan : generated->scans)
    (scan.purpose == sim::ScanPurpose::kFit ? set.views : set.validation).push_back(scan);
  for (std::size_t v = 0; v < set.views.size() && options.link_radius > 0; ++v) {
    // A sweep's links along its motion, a view's where it stands.
    if (!sim::MoveIsFree(nominal, scene, set.views[v].start, set.views[v].end, options.link_radius))
      set.colliding.push_back(static_cast<int>(v));
  }
  Say(progress, "generated " + std::to_string(set.views.size()) + " candidate views (" +
                    std::to_string(set.colliding.size()) + " with links colliding)");
  auto simulated = SimulateViews(nominal, sensor, scene, set.views, options.planning_cells,
                                 options.min_coverage, progress);
  if (!simulated) return simulated.error();
  set.thinning = simulated->thinning;
  set.sighted = simulated->sighted;
  if (set.sighted.size() < 2) {
    return Error{"planner: " + std::to_string(set.sighted.size()) + " of " +
                 std::to_string(set.views.size()) +
                 " candidate views see the scene; need at least 2 (widen the view ranges or move "
                 "the target)"};
  }
  set.sigma_m = MatchSigma(sensor, simulated->datasets);
  calib::CalibrationOptions matching = engine;
  matching.threads = options.threads;
  matching.query_stride =
      std::max(1, engine.query_stride / std::min(set.thinning.along, set.thinning.lines));
  // Thinned points lie further apart: a match's partner too.
  matching.d_max = engine.d_max * std::max(set.thinning.along, set.thinning.lines);
  set.information_factor = simulated->measurements_per_kept *
                           (matching.query_stride * matching.query_stride) /
                           (engine.query_stride * engine.query_stride);
  std::vector<bool> all(simulated->datasets.size(), true);
  const auto pairs = calib::AllPairs(all);
  Say(progress, "matching " + std::to_string(pairs.size()) + " pairs of candidate views");
  auto information = calib::LinearizePairsAt(simulated->datasets, nominal, matching, pairs,
                                             HeldByTheCalibration(sensor, engine));
  if (!information) return Error{"planner: " + information.error().message};
  set.information = std::move(information).value();
  Say(progress, std::to_string(set.information.pairs.size()) + " pairs overlap");
  MaskUnobservable(set);
  set.seconds = SecondsSince(start);
  return set;
}

namespace {

// The selection's arithmetic over the kept parameters and the held intrinsics (normalized
// units): each pair's J^T J over both, scaled to the sensor's measurements, the prior P on the
// kept ones and the position Gram matrix of the prediction.
class Selection {
 public:
  Selection(const CandidateSet& set, const PlannerOptions& options)
      : n_(set.sighted.size()), index_(n_ * n_, -1), eligible_(n_, true) {
    for (std::size_t d = 0; d < n_; ++d) {
      eligible_[d] = std::find(set.colliding.begin(), set.colliding.end(), set.sighted[d]) ==
                     set.colliding.end();
    }
    std::vector<std::size_t> kept = set.selection_free;  // then the held columns
    const std::size_t estimated = set.information.EstimatedCount();
    for (std::size_t h = 0; h < set.information.held; ++h) kept.push_back(estimated + h);
    const long k = static_cast<long>(set.selection_free.size());
    const long columns = static_cast<long>(kept.size());
    held_sd_ = set.information.held_sd;
    for (const auto& pair : set.information.pairs) {
      Eigen::MatrixXd hessian(columns, columns);
      for (long r = 0; r < columns; ++r)
        for (long c = 0; c < columns; ++c)
          hessian(r, c) = pair.normal.hessian(static_cast<long>(kept[static_cast<std::size_t>(r)]),
                                              static_cast<long>(kept[static_cast<std::size_t>(c)]));
      index_[pair.dataset_i * n_ + pair.dataset_j] = index_[pair.dataset_j * n_ + pair.dataset_i] =
          static_cast<int>(hessians_.size());
      hessians_.push_back(hessian * set.information_factor);
    }
    free_ = KeptFree(set);
    const double scale = set.information.scale_m;
    to_si_ = ToSi(set.nominal, free_, scale);
    prior_ = Eigen::MatrixXd::Zero(k, k);
    for (long c = 0; c < k; ++c) {
      const double sigma = IsTranslationParameter(set.nominal, free_[static_cast<std::size_t>(c)])
                               ? options.prior_m / scale
                               : options.prior_rad;
      prior_(c, c) = 1.0 / (sigma * sigma);
    }
    const Eigen::MatrixXd gram = calib::MeanPositionGram(
        set.nominal, free_,
        RandomConfigurations(set.nominal, calib::kPredictionSamples, calib::kPredictionSeed));
    gram_ = to_si_.asDiagonal() * gram * to_si_.asDiagonal();
    sigma2_ = set.sigma_m * set.sigma_m / (scale * scale);
  }

  static std::vector<std::size_t> KeptFree(const CandidateSet& set) {
    std::vector<std::size_t> free;
    for (std::size_t c : set.selection_free) free.push_back(set.information.free[c]);
    return free;
  }
  std::size_t Count() const { return n_; }
  bool Eligible(std::size_t d) const { return eligible_[d]; }
  long Parameters() const { return prior_.rows(); }
  long Columns() const { return Parameters() + held_sd_.size(); }
  const Eigen::MatrixXd* Pair(std::size_t a, std::size_t b) const {
    const int i = index_[a * n_ + b];
    return i < 0 ? nullptr : &hessians_[static_cast<std::size_t>(i)];
  }
  // H_S over the datasets `chosen` (kept and held columns).
  Eigen::MatrixXd Sum(const std::vector<std::size_t>& chosen) const {
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(Columns(), Columns());
    for (std::size_t a = 0; a < chosen.size(); ++a)
      for (std::size_t b = a + 1; b < chosen.size(); ++b)
        if (const auto* pair = Pair(chosen[a], chosen[b])) sum += *pair;
    return sum;
  }
  // What the selection ranks by: the predicted sensor position RMS [m], sqrt(trace(C Gram)),
  // of the scans' part of C alone, sigma^2 (H_ee + P)^-1.
  double Score(const Eigen::MatrixXd& hessian) const {
    const Eigen::LLT<Eigen::MatrixXd> llt(Estimated(hessian));
    return std::sqrt(std::max(sigma2_ * llt.solve(gram_).trace(), 0.0));
  }
  // The whole prediction: the scans' part plus what the held intrinsics' uncertainty moves the
  // estimate by (the consider covariance of covariance.h, D Sigma_h D^T, D = (H_ee + P)^-1 H_eh).
  double Total(const Eigen::MatrixXd& hessian) const {
    const Eigen::LLT<Eigen::MatrixXd> llt(Estimated(hessian));
    const Eigen::MatrixXd d = llt.solve(Cross(hessian));
    const double held = (d.transpose() * gram_ * d * held_sd_.cwiseAbs2().asDiagonal()).trace();
    return std::sqrt(std::max(sigma2_ * llt.solve(gram_).trace() + held, 0.0));
  }
  // C in SI; with `held_only` its held part alone.
  Eigen::MatrixXd CovarianceSi(const Eigen::MatrixXd& hessian, bool held_only = false) const {
    const Eigen::LLT<Eigen::MatrixXd> llt(Estimated(hessian));
    const Eigen::MatrixXd d = llt.solve(Cross(hessian));
    Eigen::MatrixXd covariance = d * held_sd_.cwiseAbs2().asDiagonal() * d.transpose();
    if (!held_only)
      covariance += sigma2_ * llt.solve(Eigen::MatrixXd::Identity(Parameters(), Parameters()));
    return to_si_.asDiagonal() * covariance * to_si_.asDiagonal();
  }
  const std::vector<std::size_t>& free() const { return free_; }

 private:
  std::size_t n_;
  std::vector<int> index_;      // n x n: into hessians_, -1 = the pair has no match
  std::vector<bool> eligible_;  // per dataset: its links are clear of the scene
  std::vector<Eigen::MatrixXd> hessians_;
  Eigen::MatrixXd Estimated(const Eigen::MatrixXd& hessian) const {
    return hessian.topLeftCorner(Parameters(), Parameters()) + prior_;
  }
  Eigen::MatrixXd Cross(const Eigen::MatrixXd& hessian) const {
    return hessian.topRightCorner(Parameters(), held_sd_.size());
  }

  std::vector<std::size_t> free_;
  Eigen::VectorXd held_sd_;
  Eigen::VectorXd to_si_;
  Eigen::MatrixXd prior_, gram_;
  double sigma2_ = 0;
};

calib::PredictedError Predict(const CandidateSet& set, const Selection& selection,
                              const std::vector<std::size_t>& chosen, bool held_only = false) {
  return calib::PredictPoseError(set.nominal, selection.free(),
                                 selection.CovarianceSi(selection.Sum(chosen), held_only),
                                 calib::kPredictionSamples, calib::kPredictionSeed);
}

// The pair of datasets with the lowest score.
std::vector<std::size_t> BestPair(const Selection& selection, double& score) {
  std::vector<std::size_t> best;
  score = std::numeric_limits<double>::infinity();
  for (std::size_t a = 0; a < selection.Count(); ++a) {
    for (std::size_t b = a + 1; b < selection.Count(); ++b) {
      const auto* pair = selection.Pair(a, b);
      if (pair == nullptr || !selection.Eligible(a) || !selection.Eligible(b)) continue;
      const double value = selection.Score(*pair);
      if (value < score) score = value, best = {a, b};
    }
  }
  return best;
}

// The dataset whose pairs with `chosen` lower the score of `sum` most (none: Count()).
std::size_t BestAddition(const Selection& selection, const std::vector<std::size_t>& chosen,
                         const Eigen::MatrixXd& sum, double& score) {
  std::vector<bool> taken(selection.Count(), false);
  for (std::size_t c : chosen) taken[c] = true;
  std::size_t best = selection.Count();
  score = std::numeric_limits<double>::infinity();
  for (std::size_t candidate = 0; candidate < selection.Count(); ++candidate) {
    if (taken[candidate] || !selection.Eligible(candidate)) continue;
    Eigen::MatrixXd with = sum;
    for (std::size_t c : chosen)
      if (const auto* pair = selection.Pair(candidate, c)) with += *pair;
    const double value = selection.Score(with);
    if (value < score) score = value, best = candidate;
  }
  return best;
}

}  // namespace

calib::PredictedError PredictForViews(const CandidateSet& candidates,
                                      const std::vector<int>& generator_indices,
                                      const PlannerOptions& options) {
  const Selection selection(candidates, options);
  std::vector<std::size_t> chosen;
  for (int view : generator_indices) {
    const auto it = std::find(candidates.sighted.begin(), candidates.sighted.end(), view);
    if (it != candidates.sighted.end())
      chosen.push_back(static_cast<std::size_t>(it - candidates.sighted.begin()));
  }
  return Predict(candidates, selection, chosen);
}

InformationPlan ChooseScans(const CandidateSet& candidates, const PlannerOptions& options,
                            const PlanProgress& progress) {
  const auto start = std::chrono::steady_clock::now();
  const Selection selection(candidates, options);
  InformationPlan result;
  double score = 0;
  std::vector<std::size_t> chosen = BestPair(selection, score);
  if (chosen.empty()) return result;  // no pair overlaps: MakeCandidates' caller says so
  Eigen::MatrixXd sum = selection.Sum(chosen);
  result.predicted_rms_m.push_back(selection.Total(sum));
  auto met = [&] {
    return options.target_m > 0 && result.predicted_rms_m.back() <= options.target_m;
  };
  while (static_cast<int>(chosen.size()) < options.max_scans &&
         !(static_cast<int>(chosen.size()) >= options.min_scans && met())) {
    const std::size_t next = BestAddition(selection, chosen, sum, score);
    if (next == selection.Count()) break;
    for (std::size_t c : chosen)
      if (const auto* pair = selection.Pair(next, c)) sum += *pair;
    chosen.push_back(next);
    result.predicted_rms_m.push_back(selection.Total(sum));
    char line[128];
    std::snprintf(line, sizeof(line), "scan %zu: view %d, predicted sensor position %.3f mm RMS",
                  chosen.size(), candidates.sighted[next], result.predicted_rms_m.back() * 1e3);
    Say(progress, line);
  }
  result.target_met = met() && static_cast<int>(chosen.size()) >= options.min_scans;
  for (std::size_t c : chosen) {
    result.chosen.push_back(candidates.sighted[c]);
    result.plan.scans.push_back(candidates.views[static_cast<std::size_t>(candidates.sighted[c])]);
  }
  for (const auto& scan : candidates.validation) result.plan.scans.push_back(scan);
  result.predicted = Predict(candidates, selection, chosen);
  result.predicted_held = Predict(candidates, selection, chosen, true);
  result.seconds = SecondsSince(start);
  return result;
}

}  // namespace selfcal::plan
