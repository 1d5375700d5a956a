#include "core/sim/ground_truth.h"

#include <algorithm>
#include <cmath>

#include "core/model/evaluation.h"
#include "core/sim/ik.h"
#include "core/sim/random.h"

namespace selfcal::sim {

RobotModel PerturbModel(const RobotModel& nominal, std::uint64_t seed,
                        const PerturbationOptions& options) {
  const std::vector<double> k0 = ToParameterVector(nominal);
  std::vector<double> direction(k0.size(), 0.0);
  Random random(SubKey(seed, 0x7e0757));
  for (std::size_t i = 0; i < k0.size(); ++i) {
    const double g = random.Gaussian();  // drawn for every index: the layout fixes the stream
    if (i >= nominal.mask.size() || !nominal.mask[i]) continue;
    direction[i] =
        g * (IsTranslationParameter(nominal, i) ? options.translation_sigma : options.angle_sigma);
  }
  Random configuration_random(SubKey(seed, 0x5a3b1e));
  std::vector<std::vector<double>> configurations;
  for (int k = 0; k < options.samples; ++k)
    configurations.push_back(RandomConfiguration(nominal, 0.0, configuration_random));
  RobotModel truth = nominal;
  auto apply = [&](double scale) {
    std::vector<double> k = k0;
    for (std::size_t i = 0; i < k.size(); ++i) k[i] += scale * direction[i];
    FromParameterVector(k, truth);
    return SensorPoseError(truth, nominal, configurations).rms_position_m;
  };
  // The error grows almost linearly with the scale: a few secant steps reach the target.
  double scale = 1.0;
  for (int iteration = 0; iteration < 8; ++iteration) {
    const double rms = apply(scale);
    if (std::abs(rms - options.target_position_rms) < 0.01 * options.target_position_rms) break;
    if (rms <= 0) break;
    scale *= options.target_position_rms / rms;
  }
  return truth;
}

}  // namespace selfcal::sim
