#include "core/calib/validation_residuals.h"

#include <algorithm>
#include <memory>

#include "core/calib/chain.h"
#include "core/calib/pair_information.h"
#include "core/calib/pair_matching.h"
#include "core/calib/parallel.h"
#include "core/calib/pose_knots.h"
#include "core/calib/projection.h"
#include "core/model/normalization.h"

namespace selfcal::calib {
namespace {

// EngineScale, or 1 where it cannot be computed (no fit scan).
double ScaleOf(const std::vector<Dataset>& datasets, const RobotModel& model) {
  const double scale = EngineScale(datasets, model);
  return scale > 0 ? scale : 1.0;
}

// The datasets projected, filtered and matched at `model`, as Calibrate() does at k_hat.
class MatcherAtModel {
 public:
  MatcherAtModel(const std::vector<Dataset>& datasets, const RobotModel& model,
                 const CalibrationOptions& options, double scale)
      : scale_(scale > 0 ? scale : ScaleOf(datasets, model)),
        chain_(ChainOf(model, scale_)),
        threads_(options.threads > 0 ? options.threads : DefaultThreadCount()),
        knots_(BuildAllPoseKnots(datasets, threads_, options.knot_max_joint_step)) {
    std::vector<double> k_hat = ToParameterVector(model);
    NormalizeTranslationParameters(k_hat, model.JointCount(), scale_);
    matcher_ = std::make_unique<PairMatcher>(datasets, chain_, knots_, options, threads_);
    matcher_->Prepare(k_hat);
  }
  MatcherAtModel(MatcherAtModel&&) = delete;  // the matcher refers to chain_ and knots_
  const PairMatcher& matcher() const { return *matcher_; }
  std::vector<ProjectedCloud> TakeClouds() { return matcher_->TakeClouds(); }
  double scale() const { return scale_; }
  int threads() const { return threads_; }

 private:
  double scale_;
  Chain chain_;
  int threads_;
  std::vector<PoseKnots> knots_;
  std::unique_ptr<PairMatcher> matcher_;
};

std::vector<bool> ValidationFlags(const std::vector<Dataset>& datasets) {
  std::vector<bool> validation(datasets.size());
  for (std::size_t d = 0; d < datasets.size(); ++d) validation[d] = datasets[d].validation;
  return validation;
}

bool AnyValidation(const std::vector<Dataset>& datasets) {
  return std::any_of(datasets.begin(), datasets.end(),
                     [](const Dataset& dataset) { return dataset.validation; });
}

}  // namespace

std::vector<float> ValidationResiduals(const std::vector<Dataset>& datasets,
                                       const RobotModel& model, const CalibrationOptions& options,
                                       double scale) {
  if (!AnyValidation(datasets)) return {};
  const MatcherAtModel at_model(datasets, model, options, scale);
  const PairMatcher& matcher = at_model.matcher();
  std::vector<float> residuals;
  for (const DatasetPair& pair : PairsTouching(ValidationFlags(datasets))) {
    const PairMatches matches = matcher.MatchPair(pair);
    const ProjectedCloud& cloud_i = matcher.clouds()[matches.dataset_i];
    const ProjectedCloud& cloud_j = matcher.clouds()[matches.dataset_j];
    for (std::size_t m = 0; m < matches.size(); ++m) {
      const float r = (cloud_i.Point(matches.point_i[m]) - cloud_j.Point(matches.point_j[m]))
                          .dot(cloud_i.Normal(matches.point_i[m]));
      residuals.push_back(r * static_cast<float>(at_model.scale()));
    }
  }
  return residuals;
}

HeldOutRegistration RegisterHeldOutScans(const std::vector<Dataset>& datasets,
                                         const RobotModel& model, const CalibrationOptions& options,
                                         double scale) {
  if (!AnyValidation(datasets)) return {};
  MatcherAtModel at_model(datasets, model, options, scale);
  return RegisterHeldOutScans(datasets, at_model.TakeClouds(), options.d_max, options.f_min,
                              options.reject_coverage_border, at_model.scale(), at_model.threads());
}

}  // namespace selfcal::calib
