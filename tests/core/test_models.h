// Robot models for the kinematics tests: random geometry, any mix of joint types.
#pragma once

#include <random>
#include <string>
#include <vector>

#include "core/model/robot_model.h"

namespace selfcal::testing {

// A model with the given joint types and parameters drawn from `seed`: angles in [-pi, pi],
// translations in [-0.5, 0.5] m, limits [-2.5, 2.5] rad or [-0.3, 0.4] m.
inline RobotModel RandomModel(const std::vector<JointType>& types, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> angle(-3.14159, 3.14159);
  std::uniform_real_distribution<double> length(-0.5, 0.5);
  RobotModel model;
  // Names built with append: GCC 12's -Wrestrict misfires on "literal" + std::string at -O3.
  model.name = "random_";
  model.name.append(std::to_string(seed));
  for (std::size_t i = 0; i < types.size(); ++i) {
    const bool revolute = types[i] == JointType::kRevolute;
    std::string name = "J";
    name.append(std::to_string(i + 1));
    model.joints.push_back(
        {name, types[i], revolute ? -2.5 : -0.3, revolute ? 2.5 : 0.4, 1.0, 2.0});
  }
  auto full = [&] {
    return FullTransformParams{angle(rng),  angle(rng),  angle(rng),
                               length(rng), length(rng), length(rng)};
  };
  model.base = full();
  for (std::size_t i = 0; i + 1 < types.size(); ++i) {
    model.segments.push_back({angle(rng), angle(rng), length(rng), length(rng)});
  }
  model.tool = full();
  model.mask = DefaultMask(model);
  return model;
}

}  // namespace selfcal::testing
