// Everything a simulation needs before it runs, from a scenario: the robot and sensor files read
// and checked, the nominal model (robot file + sensor mount), the seeded truth, the scene.
#pragma once

#include "core/model/robot_model.h"
#include "core/sim/scene.h"
#include "core/sim/sensor_model.h"
#include "core/util/expected.h"
#include "protocols/scenario/scenario_file.h"

namespace selfcal {

struct SimulationSetup {
  Scenario scenario;  // with the plan's joint speed and view target filled in
  RobotModel nominal;
  RobotModel truth;  // the simulated arm, with the scenario's truth.joint_offsets
  // The truth before those offsets: the model of the arm before a swap, as a calibration with
  // elasticity would have installed it (the effect's masses and compliance, when it is on).
  RobotModel installed;
  sim::SensorModel sensor;
  sim::Scene scene;
};

enum class SetupUse { kSimulation, kPlanningOnly };

// Errors name the file (and key) at fault, e.g. a plan kind that does not suit the sensor. A
// cell scene (free space, no surfaces) is refused unless `use` is kPlanningOnly.
Expected<SimulationSetup> PrepareSimulation(Scenario scenario,
                                            SetupUse use = SetupUse::kSimulation);

}  // namespace selfcal
