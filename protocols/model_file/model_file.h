// The robot model file of DESIGN.md: the contract every tool and test reads and writes.
#pragma once

#include <string>

#include "core/model/robot_model.h"
#include "core/util/enum_names.h"
#include "core/util/expected.h"

namespace selfcal {

// The model files' (and URDF's) spelling of each joint type.
inline constexpr EnumNames<JointType, 2> kJointTypeNames{{
    {JointType::kRevolute, "revolute"},
    {JointType::kPrismatic, "prismatic"},
}};

struct ModelFile {
  RobotModel model;              // mask filled in: from `calibrate:` or the paper's default
  bool mask_given = false;       // whether the file had a `calibrate:` section
  std::string calibration_yaml;  // the `calibration:` section as YAML text; empty when absent
};

// Strict reading: unknown keys, missing keys, wrong types and wrong counts are errors that
// name the file and the key.
Expected<ModelFile> ReadModelFile(const std::string& path);
Expected<ModelFile> ParseModelFile(const std::string& text, const std::string& name);

// YAML text of `model`; numbers with round-trip precision. `calibration_yaml`, when not empty,
// must be a YAML mapping; it is written under `calibration:`.
std::string FormatModelFile(const RobotModel& model, const std::string& calibration_yaml = {});

// Writes the file atomically.
Status WriteModelFile(const std::string& path, const RobotModel& model,
                      const std::string& calibration_yaml = {});

}  // namespace selfcal
