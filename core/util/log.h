// The one log-level and log-sink type. Library code never prints: it logs through the sink its
// owner gave it (the programs pass protocols/program's spdlog sink; tests collect messages).
#pragma once

#include <functional>
#include <string>

namespace selfcal {

enum class LogLevel { kDebug, kInfo, kWarning, kError };

using LogSink = std::function<void(LogLevel level, const std::string& message)>;

}  // namespace selfcal
