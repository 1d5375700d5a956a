// The `effects:` section of a scenario file (docs/simulation.md, "Field effects"): each key
// present turns its effect on, its fields optional with documented defaults; the section
// absent leaves every effect off. Read strictly like the rest of the file.
#pragma once

#include <string>

#include "core/sim/field_effects.h"
#include "protocols/model_file/yaml_reader.h"

namespace selfcal {

void ReadEffects(yaml::StrictMap map, sim::FieldEffects& effects);

// The enabled effects with every field, as the `effects:` section (empty when none is on, so
// that a scenario without effects formats as before).
std::string FormatEffects(const sim::FieldEffects& effects);

// Joint elasticity defaults for the KUKA LBR iiwa (7 joints): link masses of Drake's iiwa14 URDF
// and a stated stiffness (docs/simulation.md).
sim::JointElasticityEffect IiwaElasticity();

}  // namespace selfcal
