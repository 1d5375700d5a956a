// URDF (liburdfdom) <-> MCPC. Import takes the serial chain from a base link to a tip link,
// folds fixed joints into their neighbours and converts with ChainToMcpc (core/model/chain.h);
// export writes one URDF joint per MCPC joint with the MCPC transform as its origin.
// docs/kinematics.md, "Import and export", lists what each direction keeps and drops.
#pragma once

#include <string>
#include <vector>

#include "core/model/chain.h"
#include "core/model/robot_model.h"
#include "core/util/expected.h"

namespace selfcal {

struct UrdfImportOptions {
  std::string base_link;  // empty: the URDF's root link
  std::string tip_link;   // empty: the only leaf below the base (error when there are several)
  // URDF has no acceleration limits; joints without a velocity limit get the default too.
  double default_max_velocity = 1.0;      // rad/s or m/s
  double default_max_acceleration = 5.0;  // rad/s^2 or m/s^2
};

// The chain base -> tip of a URDF document. `name` names the document in errors.
// Errors: XML or URDF errors (with urdfdom's message), unknown links, several candidate tips,
// floating, planar or mimic joints on the chain, no movable joint, non-finite numbers.
// Continuous joints get limits [-pi, pi] (noted in `notes`).
Expected<GenericChain> ParseUrdfChain(const std::string& xml, const std::string& name,
                                      const UrdfImportOptions& options,
                                      std::vector<std::string>* notes = nullptr);

// ParseUrdfChain then ChainToMcpc; the notes of both steps are merged.
Expected<McpcConversion> ImportUrdf(const std::string& xml, const std::string& name,
                                    const UrdfImportOptions& options);
Expected<McpcConversion> ReadUrdfFile(const std::string& path, const UrdfImportOptions& options);

// URDF text of `model`: links "base_link", "<joint>_link" ..., "tool_link"; joint i has origin
// st(s_{i-1}) (st(s_0) for the first), axis z and the model's limits; a fixed joint "tool_joint"
// carries st(s_n). Numbers with round-trip precision. Effort limits are unknown and written as 0.
std::string FormatUrdf(const RobotModel& model);

// FormatUrdf, written atomically.
Status WriteUrdfFile(const std::string& path, const RobotModel& model);

}  // namespace selfcal
