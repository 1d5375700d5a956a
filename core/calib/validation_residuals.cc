#include "core/calib/validation_residuals.h"

#include "core/calib/chain.h"
#include "core/calib/pair_matching.h"
#include "core/calib/parallel.h"
#include "core/calib/pose_knots.h"
#include "core/calib/projection.h"
#include "core/model/normalization.h"

namespace selfcal::calib {
namespace {

double ScaleOf(const std::vector<Dataset>& datasets, const RobotModel& model) {
  const std::vector<double> k = ToParameterVector(model);
  for (const Dataset& dataset : datasets) {
    if (!dataset.validation) {
      return NormalizationScale(
          BasePoints(dataset, Chain{JointTypes(model), 1.0, false}, k.data()));
    }
  }
  return 1.0;
}

}  // namespace

std::vector<float> ValidationResiduals(const std::vector<Dataset>& datasets,
                                       const RobotModel& model, const CalibrationOptions& options,
                                       double scale) {
  std::vector<bool> validation(datasets.size());
  bool any = false;
  for (std::size_t d = 0; d < datasets.size(); ++d) any |= validation[d] = datasets[d].validation;
  if (!any) return {};
  if (!(scale > 0)) scale = ScaleOf(datasets, model);
  Chain chain{JointTypes(model), scale, false};
  for (JointType type : chain.joint_types) chain.has_prismatic |= type == JointType::kPrismatic;
  std::vector<double> k_hat = ToParameterVector(model);
  NormalizeTranslationParameters(k_hat, model.JointCount(), scale);
  const int threads = options.threads > 0 ? options.threads : DefaultThreadCount();
  std::vector<PoseKnots> knots(datasets.size());
  ParallelFor(datasets.size(), threads,
              [&](std::size_t d) { knots[d] = BuildPoseKnots(datasets[d]); });
  PairMatcher matcher(datasets, chain, knots, options, threads);
  matcher.Prepare(k_hat);
  std::vector<float> residuals;
  for (const DatasetPair& pair : PairsTouching(validation)) {
    const PairMatches matches = matcher.MatchPair(pair);
    const ProjectedCloud& cloud_i = matcher.clouds()[matches.dataset_i];
    const ProjectedCloud& cloud_j = matcher.clouds()[matches.dataset_j];
    for (std::size_t m = 0; m < matches.size(); ++m) {
      const float r = (cloud_i.Point(matches.point_i[m]) - cloud_j.Point(matches.point_j[m]))
                          .dot(cloud_i.Normal(matches.point_i[m]));
      residuals.push_back(r * static_cast<float>(scale));
    }
  }
  return residuals;
}

}  // namespace selfcal::calib
