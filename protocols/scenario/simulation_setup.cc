#include "protocols/scenario/simulation_setup.h"

#include "core/model/joint_offsets.h"
#include "core/sim/ground_truth.h"
#include "core/sim/mount.h"
#include "core/sim/random.h"
#include "protocols/model_file/model_file.h"
#include "protocols/model_file/sensor_config.h"
#include "protocols/scenario/sensor_model_config.h"

namespace selfcal {
namespace {

constexpr std::uint64_t kTruthLabel = 0x7247;

bool PlanSuitsSensor(sim::PlanOptions::Kind plan, SensorLayout sensor) {
  switch (plan) {
    case sim::PlanOptions::Kind::kStationaryViews:
      return sensor == SensorLayout::kDepthCamera;
    case sim::PlanOptions::Kind::kLineSweeps:
      return sensor == SensorLayout::kLineScanner;
    case sim::PlanOptions::Kind::kLidarSweeps:
      return sensor == SensorLayout::kRotatingLidar;
  }
  return false;
}

}  // namespace

Expected<SimulationSetup> PrepareSimulation(Scenario scenario, SetupUse use) {
  SimulationSetup setup;
  const auto robot_file = ReadModelFile(scenario.robot_path);
  if (!robot_file) return robot_file.error();
  const auto sensor_config = ReadSensorConfig(scenario.sensor_path);
  if (!sensor_config) return sensor_config.error();
  if (const std::string problem = CheckCameraBinning(*sensor_config, scenario.camera_binning);
      !problem.empty()) {
    return Error{"scenario " + scenario.name + ": key 'camera_binning' " + problem + " (" +
                 scenario.sensor_path + ")"};
  }
  setup.sensor = ToSensorModel(*sensor_config, scenario.camera_binning);
  if (const std::string problem = sim::CheckSensorModel(setup.sensor); !problem.empty()) {
    return Error{scenario.sensor_path + ": " + problem};
  }
  if (!PlanSuitsSensor(scenario.plan.kind, setup.sensor.kind)) {
    return Error{"scenario " + scenario.name +
                 ": key 'plan.kind' does not suit the sensor's layout " +
                 kSensorLayoutNames.Name(setup.sensor.kind) + " (" + scenario.sensor_path + ")"};
  }
  if (setup.sensor.kind == SensorLayout::kRotatingLidar) {
    scenario.plan.joint_speed = sim::LidarJointSpeed(setup.sensor, scenario.lidar_line_spacing);
  }
  auto scene = sim::BuildScene(scenario.scene);
  if (!scene) return Error{"scenario " + scenario.name + ": " + scene.error().message};
  if (use == SetupUse::kSimulation && !sim::HasSurfaces(*scene)) {
    return Error{"scenario " + scenario.name +
                 ": its scene is a cell's free space, with nothing to see: it plans scans "
                 "(selfcal daemon-plan) but cannot be simulated"};
  }
  setup.scene = std::move(*scene);
  if (!scenario.view_target_given) {
    scenario.plan.view.target = setup.scene.focus;
    scenario.view_target_given = true;
  }
  if (const auto& elasticity = scenario.recording.effects.joint_elasticity;
      elasticity.enabled && elasticity.stiffness.size() != robot_file->model.JointCount()) {
    return Error{
        "scenario " + scenario.name +
        ": key 'effects.joint_elasticity' needs one stiffness and link mass per joint of " +
        scenario.robot_path};
  }
  setup.nominal = sim::WithSensorMount(robot_file->model, scenario.mount);
  setup.installed =
      sim::PerturbModel(setup.nominal, sim::SubKey(scenario.seed, kTruthLabel), scenario.truth);
  setup.truth = setup.installed;
  if (!scenario.truth_joint_offsets.empty()) {
    if (scenario.truth_joint_offsets.size() != setup.installed.JointCount()) {
      return Error{"scenario " + scenario.name + ": key 'truth.joint_offsets' has " +
                   std::to_string(scenario.truth_joint_offsets.size()) + " values, " +
                   scenario.robot_path + " has " + std::to_string(setup.installed.JointCount()) +
                   " joints"};
    }
    auto swapped = WithJointOffsets(setup.installed, scenario.truth_joint_offsets);
    if (!swapped) return Error{"scenario " + scenario.name + ": " + swapped.error().message};
    setup.truth = std::move(*swapped);
  }
  // The truth files stay rigid (the deflection is an effect of the simulation); the installed
  // model knows the sag, so that a remastering starts where the site's model was.
  if (const auto& elasticity = scenario.recording.effects.joint_elasticity; elasticity.enabled) {
    setup.installed.gravity = {elasticity.link_masses, elasticity.sensor_mass, {}};
    setup.installed.compliance.clear();
    for (double stiffness : elasticity.stiffness)
      setup.installed.compliance.push_back(stiffness > 0 ? 1 / stiffness : 0.0);
  }
  setup.scenario = std::move(scenario);
  return setup;
}

}  // namespace selfcal
