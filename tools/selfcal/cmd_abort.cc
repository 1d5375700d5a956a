// `selfcal abort`: stops the running session at once (a signed ABORT request).
#include "selfcal/calibration_request_t.hpp"
#include "tools/selfcal/commands.h"
#include "tools/selfcal/daemon_client.h"

namespace selfcal::cli {

void RegisterAbort(CLI::App& app) {
  AddPlainRequestCommand(app, "abort", "Abort the running calibration session (signed request)",
                         selfcal::calibration_request_t::ABORT);
}

}  // namespace selfcal::cli
