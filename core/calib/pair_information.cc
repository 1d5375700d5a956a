#include "core/calib/pair_information.h"

#include <cmath>

#include "core/calib/parallel.h"
#include "core/calib/projection.h"
#include "core/model/kinematics.h"
#include "core/model/normalization.h"

namespace selfcal::calib {

std::vector<PairNormalEquations> LinearizeEachPair(
    const std::vector<Dataset>& datasets, const Chain& chain, const std::vector<PoseKnots>& knots,
    const PairMatcher& matcher, const std::vector<std::size_t>& free,
    const std::vector<DatasetPair>& pairs, const std::vector<double>& k_hat, int threads,
    CostKind cost, const RobustLoss& loss) {
  std::vector<PairNormalEquations> terms(pairs.size());
  ParallelFor(pairs.size(), threads, [&](std::size_t p) {
    MatchProblem pair(datasets, chain, knots, free, 1, false, cost);
    pair.SetLoss(loss);
    pair.SetMatches(
        {pairs[p]}, [&](std::size_t) { return matcher.MatchPair(pairs[p]); }, matcher.clouds(),
        k_hat);
    terms[p] = {pairs[p].first, pairs[p].second, pair.Linearize(k_hat)};
  });
  std::erase_if(terms, [](const PairNormalEquations& term) { return term.normal.residuals == 0; });
  return terms;
}

double EngineScale(const std::vector<Dataset>& datasets, const RobotModel& model) {
  std::size_t first_fit = 0;
  while (first_fit < datasets.size() && datasets[first_fit].validation) ++first_fit;
  if (first_fit == datasets.size()) return 0;
  const std::vector<double> k = ToParameterVector(model);
  const double scale = NormalizationScale(
      BasePoints(datasets[first_fit], Chain{JointTypes(model), 1.0, false}, k.data()));
  return scale > 0 && std::isfinite(scale) ? scale : 0.0;
}

Expected<PairInformation> LinearizePairsAt(const std::vector<Dataset>& datasets,
                                           const RobotModel& model,
                                           const CalibrationOptions& options,
                                           const std::vector<DatasetPair>& pairs,
                                           const HeldIntrinsics& held) {
  for (const Dataset& dataset : datasets) {
    if (dataset.joint_count != model.JointCount() || !dataset.HasJointsOfEveryPose()) {
      return Error{"scan " + std::to_string(dataset.scan_index) +
                   ": joint values inconsistent with the robot model's " +
                   std::to_string(model.JointCount()) + " joints"};
    }
    if (dataset.ValidPointCount() == 0)
      return Error{"scan " + std::to_string(dataset.scan_index) + ": no valid points"};
  }
  PairInformation information;
  information.scale_m = EngineScale(datasets, model);
  if (!(information.scale_m > 0)) return Error{"cannot compute the normalization scale s"};
  Chain chain = ChainOf(model, information.scale_m);
  for (std::size_t i = 0; i < model.mask.size(); ++i)
    if (model.mask[i]) information.free.push_back(i);
  chain.intrinsics = held.which;
  information.held = held.which.Count();
  const bool is_held[3] = {held.which.scale, held.which.offset, held.which.focal};
  std::vector<double> held_sd;
  for (int t = 0; t < 3; ++t) {
    if (!is_held[t]) continue;
    information.free.push_back(chain.FirstIntrinsic() + held_sd.size());
    held_sd.push_back(t == 1 ? held.sd[t] / information.scale_m : held.sd[t]);
  }
  information.held_sd =
      Eigen::Map<const Eigen::VectorXd>(held_sd.data(), static_cast<long>(held_sd.size()));
  const int threads = options.threads > 0 ? options.threads : DefaultThreadCount();
  const std::vector<PoseKnots> knots =
      BuildAllPoseKnots(datasets, threads, options.knot_max_joint_step);
  std::vector<double> k_hat = ToParameterVector(model);
  NormalizeTranslationParameters(k_hat, model.JointCount(), information.scale_m);
  k_hat.resize(k_hat.size() + information.held, 0.0);  // the held intrinsics at the file's values
  PairMatcher matcher(datasets, chain, knots, options, threads);
  matcher.Prepare(k_hat);
  information.pairs = LinearizeEachPair(datasets, chain, knots, matcher, information.free, pairs,
                                        k_hat, threads, options.cost, RobustLoss{});
  return information;
}

}  // namespace selfcal::calib
