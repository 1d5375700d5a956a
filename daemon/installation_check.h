// `selfcald --check`: reads everything the daemon would use at start-up (key, sensor, the model
// it would start from, every plan against that model, the storage folder's permissions) without
// writing anything, so a check can run on a live installation or before the first start.
#pragma once

#include <string>

#include "core/util/expected.h"
#include "daemon/config.h"

namespace selfcal::daemon {

// On success, one line per thing checked; on failure, the first problem, naming the file.
Expected<std::string> CheckInstallation(const DaemonConfig& config);

}  // namespace selfcal::daemon
