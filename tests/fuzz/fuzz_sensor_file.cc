// Any bytes as a sensor file (config/sensors/*.yaml): an error naming file and key, or a sensor
// whose engine options are valid and whose simulated sensor model has a finite, non-empty grid at
// every camera binning the sensor is large enough for; never a crash.
#include <cmath>
#include <cstdint>
#include <string>

#include "protocols/model_file/sensor_config.h"
#include "protocols/recording/recording.h"
#include "protocols/scenario/sensor_model_config.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const auto sensor = selfcal::ParseSensorConfig(text, "fuzz.yaml");
  if (!sensor.ok()) return 0;
  std::string why;
  if (!selfcal::recording::CalibrationOptionsFromSensor(*sensor).IsValid(&why)) __builtin_trap();
  for (const int binning : {1, 2}) {
    // A binning the sensor is too small for is refused by name before any model is made.
    if (!selfcal::CheckCameraBinning(*sensor, binning).empty()) {
      if (binning == 1) __builtin_trap();
      continue;
    }
    const auto model = selfcal::ToSensorModel(*sensor, binning);
    if (model.width < 1 || model.height < 1) __builtin_trap();
    if (!std::isfinite(model.range_min) || !std::isfinite(model.range_max)) __builtin_trap();
  }
  return 0;
}
