// Simulation scenario files (config/scenarios/*.yaml): which robot, sensor, mount, scene, scan
// plan, ground-truth perturbation and recording options. Read strictly: unknown keys and wrong
// types are errors naming file and key. docs/simulation.md describes every key.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/sim/ground_truth.h"
#include "core/sim/mount.h"
#include "core/sim/scan_plan.h"
#include "core/sim/scene.h"
#include "core/sim/simulator.h"
#include "core/util/expected.h"

namespace selfcal {

enum class CameraOutput { kDepthImage, kOrganizedCloud };

struct Scenario {
  std::string name;
  std::uint64_t seed = 1;
  std::int64_t start_utime = 1700000000000000;  // us since the epoch of the first joint state
  std::string robot_path;  // absolute after reading (relative paths are to the scenario file)
  std::string sensor_path;
  CameraOutput camera_output = CameraOutput::kDepthImage;  // depth cameras only
  int camera_binning = 1;  // depth cameras: integer resolution reduction (1 = as configured)
  double lidar_line_spacing = 2.0;  // LiDAR: line spacing / ray spacing (sets joint_speed)
  sim::SensorMount mount;           // T_flange_sensor
  sim::SceneSpec scene;
  sim::PlanOptions plan;  // plan.seed == seed; plan.view.target defaults to the scene's focus
  bool view_target_given = false;
  sim::PerturbationOptions truth;
  // `truth.joint_offsets`: per joint, base to tip, rad (m for a prismatic joint); empty = none. A
  // simulated motor or gearbox swap: the true arm is the perturbed truth with these joints turned
  // at their zeros (WithJointOffsets, core/model/joint_offsets.h), nothing else changed.
  std::vector<double> truth_joint_offsets;
  sim::RecordingOptions recording;  // recording.seed == seed
};

// Relative paths in the file are resolved against the file's folder (`directory` for text).
Expected<Scenario> ReadScenarioFile(const std::string& path);
Expected<Scenario> ParseScenario(const std::string& text, const std::string& name,
                                 const std::string& directory);

// The resolved scenario as YAML (every key, absolute paths): reading it back gives the same
// scenario.
std::string FormatScenario(const Scenario& scenario);

}  // namespace selfcal
