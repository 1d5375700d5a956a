// A sensor file (Table I values and geometry) -> the simulator's sensor model.
#pragma once

#include "core/sim/sensor_model.h"
#include "protocols/model_file/sensor_config.h"

namespace selfcal {

// `camera_binning` reduces a depth camera's resolution by that integer factor.
sim::SensorModel ToSensorModel(const SensorConfig& config, int camera_binning = 1);

}  // namespace selfcal
