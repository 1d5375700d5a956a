// Built when this tree has no calibration engine (core/calib, protocols/recording).
#include "daemon/engine.h"

namespace selfcal::daemon {

Expected<std::unique_ptr<CalibrationEngine>> MakeDefaultEngine() {
  return Error{
      "this build has no calibration engine (core/calib and protocols/recording are missing)"};
}

}  // namespace selfcal::daemon
