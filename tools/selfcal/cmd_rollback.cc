// `selfcal rollback`: reinstates the model that was current before the last accepted one
// (a signed ROLLBACK request; the daemon owns the model files).
#include "selfcal/calibration_request_t.hpp"
#include "tools/selfcal/commands.h"
#include "tools/selfcal/daemon_client.h"

namespace selfcal::cli {

void RegisterRollback(CLI::App& app) {
  AddPlainRequestCommand(app, "rollback", "Reinstate the previous robot model (signed request)",
                         selfcal::calibration_request_t::ROLLBACK);
}

}  // namespace selfcal::cli
