// The process around the Daemon: options, logging, signals, sd_notify (READY, WATCHDOG, STATUS).
// selfcald runs it with the real engine; tests run it with an engine of their own.
#pragma once

#include <functional>
#include <memory>

#include "daemon/engine.h"

namespace selfcal::daemon {

using EngineFactory = std::function<Expected<std::unique_ptr<CalibrationEngine>>()>;

int RunService(int argc, char** argv, const EngineFactory& make_engine);

}  // namespace selfcal::daemon
