#include "tools/selfcal/commands.h"

namespace selfcal::cli {

int exit_code = 0;

// One declaration and one call per subcommand, in blocks per area so that parallel work does
// not touch the same lines.
void RegisterModelCheck(CLI::App& app);
// --- kinematics ---
void RegisterFk(CLI::App& app);
void RegisterEvaluate(CLI::App& app);
void RegisterExport(CLI::App& app);
void RegisterImport(CLI::App& app);
// --- simulation ---
void RegisterSimulate(CLI::App& app);
// --- calibration ---
void RegisterCalibrate(CLI::App& app);
// --- daemon client ---
void RegisterTrigger(CLI::App& app);
void RegisterStatus(CLI::App& app);
void RegisterAbort(CLI::App& app);
void RegisterHistory(CLI::App& app);
void RegisterRollback(CLI::App& app);
void RegisterDaemonPlan(CLI::App& app);

void RegisterAll(CLI::App& app) {
  RegisterModelCheck(app);
  // --- kinematics ---
  RegisterFk(app);
  RegisterEvaluate(app);
  RegisterExport(app);
  RegisterImport(app);
  // --- simulation ---
  RegisterSimulate(app);
  // --- calibration ---
  RegisterCalibrate(app);
  // --- daemon client ---
  RegisterTrigger(app);
  RegisterStatus(app);
  RegisterAbort(app);
  RegisterHistory(app);
  RegisterRollback(app);
  RegisterDaemonPlan(app);
}

}  // namespace selfcal::cli
