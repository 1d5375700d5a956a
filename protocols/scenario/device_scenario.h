// A scenario as a device simulator serves it (selfcal-sim-scip in scene mode, the fake GigE
// camera, the OpenNI2 plugin, the fake Wenglor library): the scenario prepared as `selfcal
// simulate` prepares it (the same true arm, sensor file and scene), the scene's ray caster, and
// the frame caster of core/sim/device_frame.h with the scenario's field effects.
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "core/sim/device_frame.h"
#include "core/sim/ray_caster.h"
#include "core/sim/scan_plan.h"
#include "core/util/expected.h"
#include "protocols/scenario/simulation_setup.h"

namespace selfcal {

struct DeviceScenario {
  SimulationSetup setup;
  std::unique_ptr<sim::RayCaster> caster;
  std::unique_ptr<sim::DeviceFrameCaster> frames;  // casts in *caster
  // The scenario has an `effects:` section with an effect on: the device serves the sensor
  // file's noise and the effects through `frames`; otherwise its ideal frames as before.
  bool field = false;
};

// Errors name the scenario file (and key) at fault.
Expected<DeviceScenario> LoadDeviceScenario(const std::string& path);

// Scan `index` of the scenario's plan (MakeScanPlan on the nominal model, as `selfcal simulate`
// plans it): where a device simulator that no joint states drive stands or sweeps.
Expected<sim::PlannedScan> DeviceScenarioScan(const DeviceScenario& scenario, int index);

// How long each scan of that plan lasts from its BEGIN to its END marker [s], as `selfcal
// simulate` times it: the walker's pace in a device simulator that learns of scans by markers.
Expected<std::vector<double>> DeviceScenarioScanSeconds(const DeviceScenario& scenario);

// T_base_sensor at `fraction` (0..1) of scan `index` of that plan, where `selfcal simulate`'s true
// arm has it: deflected, behind its commands by the backlash of the moves before, the links
// grown as far as the recording has run.
Expected<Eigen::Isometry3d> DeviceScenarioSensorPose(const DeviceScenario& scenario, int index,
                                                     double fraction);

}  // namespace selfcal
