#include "core/model/kinematics.h"

#include <cstdlib>
#include <iostream>

namespace selfcal {

std::vector<JointType> JointTypes(const RobotModel& model) {
  std::vector<JointType> types;
  types.reserve(model.joints.size());
  for (const auto& joint : model.joints) types.push_back(joint.type);
  return types;
}

Transform3<double> ForwardKinematics(const RobotModel& model, std::span<const double> joints) {
  if (joints.size() != model.JointCount()) {
    std::cerr << "selfcal: ForwardKinematics: " << joints.size() << " joint values for "
              << model.JointCount() << " joints\n";
    std::abort();
  }
  const std::vector<double> parameters = ToParameterVector(model);
  const std::vector<JointType> types = JointTypes(model);
  return ForwardKinematics<double, double>(types, parameters.data(), joints.data());
}

}  // namespace selfcal
