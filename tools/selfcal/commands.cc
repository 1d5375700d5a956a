#include "tools/selfcal/commands.h"

namespace selfcal::cli {

int exit_code = 0;

// One declaration and one call per subcommand, in blocks per area so that parallel work does
// not touch the same lines.
void RegisterModelCheck(CLI::App& app);
// --- kinematics (issue 3) ---
// --- simulation (issue 3) ---
// --- calibration (issues 4, 5) ---
void RegisterCalibrate(CLI::App& app);
// --- daemon client (issue 10) ---

void RegisterAll(CLI::App& app) {
  RegisterModelCheck(app);
  // --- kinematics (issue 3) ---
  // --- simulation (issue 3) ---
  // --- calibration (issues 4, 5) ---
  RegisterCalibrate(app);
  // --- daemon client (issue 10) ---
}

}  // namespace selfcal::cli
