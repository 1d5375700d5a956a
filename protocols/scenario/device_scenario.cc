#include "protocols/scenario/device_scenario.h"

#include "core/sim/simulator.h"

namespace selfcal {

Expected<DeviceScenario> LoadDeviceScenario(const std::string& path) {
  auto scenario = ReadScenarioFile(path);
  if (!scenario) return scenario.error();
  auto setup = PrepareSimulation(std::move(scenario).value());
  if (!setup) return Error{path + ": " + setup.error().message};
  DeviceScenario device;
  device.setup = std::move(*setup);
  auto caster = sim::RayCaster::Create(device.setup.scene);
  if (!caster) return Error{path + ": " + caster.error().message};
  device.caster = std::move(*caster);
  const sim::RecordingOptions& recording = device.setup.scenario.recording;
  device.field = recording.effects.AnyEnabled();
  device.frames = std::make_unique<sim::DeviceFrameCaster>(*device.caster, device.setup.truth,
                                                           device.setup.sensor, recording.effects,
                                                           device.setup.scenario.seed);
  return device;
}

namespace {

Expected<sim::ScanPlan> DevicePlan(const SimulationSetup& setup) {
  auto plan = sim::MakeScanPlan(setup.nominal, setup.sensor, setup.scene, setup.scenario.plan);
  if (!plan) return Error{setup.scenario.name + ": " + plan.error().message};
  return plan;
}

// The scenario's recording as `selfcal simulate` lays it out (no frame is cast until asked).
Expected<std::unique_ptr<sim::Simulator>> DeviceSimulator(const DeviceScenario& scenario) {
  const SimulationSetup& setup = scenario.setup;
  auto plan = DevicePlan(setup);
  if (!plan) return plan.error();
  return std::make_unique<sim::Simulator>(setup.truth, setup.sensor, *scenario.caster,
                                          std::move(*plan), setup.scenario.recording);
}

}  // namespace

Expected<sim::PlannedScan> DeviceScenarioScan(const DeviceScenario& scenario, int index) {
  const SimulationSetup& setup = scenario.setup;
  auto plan = DevicePlan(setup);
  if (!plan) return plan.error();
  if (index < 0 || index >= static_cast<int>(plan->scans.size())) {
    return Error{setup.scenario.name + ": scan " + std::to_string(index) + " is not in its plan (" +
                 std::to_string(plan->scans.size()) + " scans)"};
  }
  return plan->scans[static_cast<std::size_t>(index)];
}

Expected<std::vector<double>> DeviceScenarioScanSeconds(const DeviceScenario& scenario) {
  auto simulator = DeviceSimulator(scenario);
  if (!simulator) return simulator.error();
  std::vector<double> seconds(static_cast<std::size_t>((*simulator)->SegmentCount()));
  for (std::size_t k = 0; k < seconds.size(); ++k) {
    seconds[k] = (*simulator)->ScanSeconds(static_cast<int>(k));
  }
  return seconds;
}

Expected<Eigen::Isometry3d> DeviceScenarioSensorPose(const DeviceScenario& scenario, int index,
                                                     double fraction) {
  auto simulator = DeviceSimulator(scenario);
  if (!simulator) return simulator.error();
  if (index < 0 || index >= (*simulator)->SegmentCount()) {
    return Error{scenario.setup.scenario.name + ": scan " + std::to_string(index) +
                 " is not in its plan (" + std::to_string((*simulator)->SegmentCount()) +
                 " scans)"};
  }
  const double t = (*simulator)->ScanBegin(index) + fraction * (*simulator)->ScanSeconds(index);
  return (*simulator)->TrueSensorPose(t);
}

}  // namespace selfcal
