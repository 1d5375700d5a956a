// The URDF writer the model store uses: every installed model also gets a model.urdf.
#pragma once

#include "daemon/model_store.h"

namespace selfcal::daemon {

UrdfExporter DefaultUrdfExporter();

}  // namespace selfcal::daemon
