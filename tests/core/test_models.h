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

// The iiwa of config/robots/kuka_lbr_iiwa_r840.yaml (axes at right angles) with a sensor mount.
inline RobotModel IiwaWithMount() {
  RobotModel model;
  model.name = "iiwa";
  for (int i = 1; i <= 7; ++i) {
    std::string name = "A";  // append: GCC 12's -Wrestrict misfires on "A" + s
    name.append(std::to_string(i));
    model.joints.push_back({name, JointType::kRevolute, -2.0, 2.0, 1.5, 5.0});
  }
  constexpr double kQuarter = 1.5707963267948966;
  model.base = {0, 0, 0, 0, 0, 0.36};
  model.segments = {{-kQuarter, 0, 0, 0}, {kQuarter, 0, 0, 0},      {kQuarter, 0, 0, 0.42},
                    {-kQuarter, 0, 0, 0}, {-kQuarter, 0, 0, -0.40}, {kQuarter, 0, 0, 0}};
  model.tool = {0, 0, 0, 0, -0.045, 0.201};
  model.mask = DefaultMask(model);
  return model;
}

}  // namespace selfcal::testing
