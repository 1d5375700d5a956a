// Any bytes as a robot model file or a sensor file: an error or a model that formats to YAML
// which reads back to the same model; never a crash.
#include <cstdint>
#include <string>

#include "protocols/model_file/model_file.h"
#include "protocols/model_file/sensor_config.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const auto model = selfcal::ParseModelFile(text, "fuzz.yaml");
  if (model.ok()) {
    // What we read we can write and read again.
    const std::string formatted = selfcal::FormatModelFile(model->model);
    const auto again = selfcal::ParseModelFile(formatted, "again.yaml");
    if (!again.ok()) __builtin_trap();
    if (selfcal::FormatModelFile(again->model) != formatted) __builtin_trap();
  }
  (void)selfcal::ParseSensorConfig(text, "fuzz.yaml");
  return 0;
}
