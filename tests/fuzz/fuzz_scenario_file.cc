// Any bytes as a simulation scenario file (config/scenarios/*.yaml, relative paths resolved
// against that folder): an error naming file and key, or a scenario that formats to YAML which
// reads back to the same scenario; never a crash.
#include <cstdint>
#include <string>

#include "protocols/scenario/scenario_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string folder = SELFCAL_SOURCE_DIR "/config/scenarios";
  const std::string text(reinterpret_cast<const char*>(data), size);
  const auto scenario = selfcal::ParseScenario(text, "fuzz.yaml", folder);
  if (!scenario.ok()) return 0;
  const std::string formatted = selfcal::FormatScenario(*scenario);
  const auto again = selfcal::ParseScenario(formatted, "again.yaml", folder);
  if (!again.ok()) __builtin_trap();
  if (selfcal::FormatScenario(*again) != formatted) __builtin_trap();
  return 0;
}
