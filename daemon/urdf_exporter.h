// The URDF writer the model store uses (protocols/model_file/urdf.* once it lands on main).
#pragma once

#include "daemon/model_store.h"

namespace selfcal::daemon {

// Empty (no URDF written) when this build has no URDF writer.
UrdfExporter DefaultUrdfExporter();

}  // namespace selfcal::daemon
