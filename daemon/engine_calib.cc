// The production engine: the code of `selfcal calibrate` (core/calib, protocols/recording).
#include "daemon/engine.h"

namespace selfcal::daemon {

Expected<std::unique_ptr<CalibrationEngine>> MakeDefaultEngine() {
  // core/calib's Calibrate() has not landed on main yet: say so instead of pretending.
  return Error{"this build has no calibration engine (core/calib is not available yet)"};
}

}  // namespace selfcal::daemon
