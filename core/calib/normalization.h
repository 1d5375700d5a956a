// The paper's "Normalization": s is the mean distance of the first dataset's points from the
// base, projected with the initial model; translations of k (and points, and prismatic joints)
// are divided by s during the optimization so that angles and translations weigh alike.
#pragma once

#include <vector>

#include "core/calib/chain.h"
#include "core/calib/dataset.h"
#include "core/model/robot_model.h"

namespace selfcal::calib {

// s [m] from `dataset` projected with the raw parameters `k` (flat layout). 0 when the dataset
// has no valid point.
double ComputeScale(const Dataset& dataset, const std::vector<JointType>& joint_types,
                    const std::vector<double>& k);

// k -> k_hat (translations divided by s) and back.
std::vector<double> NormalizeParameters(const RobotModel& model, const std::vector<double>& k,
                                        double s);
std::vector<double> DenormalizeParameters(const RobotModel& model, const std::vector<double>& k_hat,
                                          double s);

}  // namespace selfcal::calib
