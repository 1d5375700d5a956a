#include "core/calib/normalization.h"

namespace selfcal::calib {

double ComputeScale(const Dataset& dataset, const std::vector<JointType>& joint_types,
                    const std::vector<double>& k) {
  Chain chain{joint_types, 1.0, false};
  double sum = 0.0;
  std::size_t count = 0;
  const bool single_pose = dataset.layout == PoseLayout::kOnePerScan;
  Transform3<double> pose = chain.Pose(k.data(), dataset.JointsOfPose(0));
  for (std::size_t i = 0; i < dataset.PointCount(); ++i) {
    if (!dataset.IsValid(i)) continue;
    if (!single_pose) pose = chain.Pose(k.data(), dataset.JointsOfPose(dataset.PoseOf(i)));
    sum += (pose * NormalizedSensorPoint(dataset, i, 1.0)).norm();
    ++count;
  }
  return count == 0 ? 0.0 : sum / static_cast<double>(count);
}

std::vector<double> NormalizeParameters(const RobotModel& model, const std::vector<double>& k,
                                        double s) {
  std::vector<double> k_hat = k;
  for (std::size_t i = 0; i < k.size(); ++i) {
    if (IsTranslationParameter(model, i)) k_hat[i] = k[i] / s;
  }
  return k_hat;
}

std::vector<double> DenormalizeParameters(const RobotModel& model, const std::vector<double>& k_hat,
                                          double s) {
  std::vector<double> k = k_hat;
  for (std::size_t i = 0; i < k.size(); ++i) {
    if (IsTranslationParameter(model, i)) k[i] = k_hat[i] * s;
  }
  return k;
}

}  // namespace selfcal::calib
