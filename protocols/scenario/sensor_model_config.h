// A sensor file (Table I values and geometry) -> the simulator's sensor model.
#pragma once

#include <string>

#include "core/sim/sensor_model.h"
#include "protocols/model_file/sensor_config.h"

namespace selfcal {

// `camera_binning` reduces a depth camera's resolution by that integer factor.
sim::SensorModel ToSensorModel(const SensorConfig& config, int camera_binning = 1);

// Empty when `camera_binning` leaves a depth camera at least one pixel each way (or the sensor is
// not a camera); else "2 leaves no pixel of the 1080x1 sensor".
std::string CheckCameraBinning(const SensorConfig& config, int camera_binning);

}  // namespace selfcal
