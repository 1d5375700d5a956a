// Scenes for the simulated Wenglor line scanner, seen by a line scanner that sweeps back and forth
// over them: analytic ones (a ground plane, a box, a sphere; exact ray casting, no mesh) and the
// Stanford bunny on a table, ray cast by core/sim (Embree), as in the paper's wenglor-bunny runs.
// Tests compare decoded profiles against this truth to the noise level.
//
// With `scenario` set, a simulation scenario instead (a line scanner's, config/scenarios/): the
// scanner on the scenario's true arm sweeps scan `view` of its plan back and forth (start to end
// in the plan's time, then back), in the scenario's scene, with its columns, fan and working range
// as configured here. A scenario with an `effects:` section is served through
// core/sim/device_frame.h, as selfcal-sim-scip serves it: the sensor file's noise (on z) and the
// effects a device can show, with the walker (as far through its walk as the sweep has come) and
// the moved box of scan `view`, the sensor latency, backlash on the sweep's reversals and thermal
// growth on the device's clock (the time since the acquisition began); without one, the ideal
// ray casts plus `noise_sigma` along the ray, as for the other scenes. PoseAt is then
// T_base_sensor.
//
// Frames: world z up, ground plane z = 0. The sensor frame follows line_profile_t: x along the
// laser line, z along the optical axis (away from the sensor); the sensor looks straight down
// (z_sensor = -z_world, x_sensor = x_world) and sweeps along world y.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/util/expected.h"

namespace selfcal {
struct DeviceScenario;
}
namespace selfcal::sim {
class RayCaster;
}

namespace selfcal::sim_wenglor {

struct SceneConfig {
  // plane | box | sphere | objects (plane + box + sphere) | bunny (core/sim: the Stanford bunny,
  // 0.16 m high, on a table top at z = 0, under the sensor's start position)
  std::string scene = "objects";
  std::string bunny_path = "/usr/share/glmark2/models/bunny.obj";
  int columns = 1280;           // points per profile (MLSL: 1280)
  double fan_angle = 0.5;       // rad, full opening angle (config/sensors/wenglor_mlsl236.yaml)
  double z_start = 0.30;        // m, near end of the working range
  double z_range = 1.20;        // m, working range length (0.30 .. 1.50 m)
  double noise_sigma = 0.0002;  // m, range noise (Table I: 0.2 mm)
  double height = 0.80;         // m, sensor above the ground plane
  double speed = 0.20;          // m/s along world y
  double sweep_length = 0.60;   // m, the sensor sweeps y in [-sweep/2, +sweep/2] and back,
                                // starting at y = 0 (over the box) towards +y
  std::uint64_t seed = 1;
  std::string scenario;  // a scenario file; replaces `scene`
  int view = 0;          // the scan of the scenario's plan to sweep
};

struct Column {
  bool hit = false;    // false: no return within the working range (the library reports 0, 0)
  double x = 0;        // m, sensor frame
  double z = 0;        // m, sensor frame
  int intensity = 0;   // 0 .. 1023
  int peak_width = 0;  // 0 .. 31 px
};

class LineScannerScene {
 public:
  // Builds the scene (for the bunny: reads the mesh, builds the ray caster's BVH).
  static Expected<std::unique_ptr<LineScannerScene>> Create(SceneConfig config);
  explicit LineScannerScene(SceneConfig config);  // analytic scenes only
  ~LineScannerScene();

  const SceneConfig& config() const { return config_; }
  // T_world_sensor at time t [s] since the acquisition started.
  Eigen::Isometry3d PoseAt(double t) const;
  // The exact profile at time t (no noise).
  void Trace(double t, std::vector<Column>& columns) const;
  // The measured profile: exact range plus Gaussian noise, deterministic in (seed, index).
  void Measure(double t, std::uint64_t index, std::vector<Column>& columns) const;
  // Direction of column i in the sensor frame (unit vector in the xz plane).
  Eigen::Vector3d RayDirection(int column) const;
  // The scenario's, or null.
  const DeviceScenario* scenario() const { return scenario_.get(); }
  // A scenario's joint positions at time t (the sweep back and forth); empty without one.
  std::vector<double> JointsAt(double t) const;
  // Where the arm's joints are when the profile stamped t is measured: with effects, at t plus
  // the scenario's sensor latency, behind the sweep by its backlash (the play operator over the
  // passes so far); otherwise JointsAt(t).
  std::vector<double> ArmJointsAt(double t) const;
  // How far the sweep has come at time t: 0 at the scan's start, 1 at its end.
  double SweepFraction(double t) const;

 private:
  // Distance along the ray to the nearest surface, and the cosine of the incidence angle.
  bool Cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double& range,
            double& cos_incidence) const;
  void Fill(double t, const std::uint64_t* noise_index, std::vector<Column>& columns) const;
  // A scenario with effects: the profile of core/sim/device_frame.h.
  void FillField(double t, std::uint64_t index, std::vector<Column>& columns) const;
  Expected<bool> LoadScenario();
  // When the profile stamped t is measured [s on the device's clock]: t + the latency (effects).
  double MeasuredAt(double t) const;

  SceneConfig config_;
  std::unique_ptr<sim::RayCaster> mesh_caster_;  // the bunny scene; null for analytic scenes
  std::unique_ptr<DeviceScenario> scenario_;     // with config_.scenario
  std::vector<double> sweep_start_, sweep_end_;  // the scenario's scan
  double pass_time_ = 1;                         // s from start to end
  bool has_box_ = false;
  bool has_sphere_ = false;
  Eigen::Vector3d box_min_{-0.10, -0.08, 0.0};
  Eigen::Vector3d box_max_{0.10, 0.08, 0.20};
  Eigen::Vector3d sphere_center_{0.16, 0.12, 0.12};
  double sphere_radius_ = 0.12;
};

// Parses a scene name; false when unknown.
bool IsKnownScene(const std::string& name);
bool IsAnalyticScene(const std::string& name);

}  // namespace selfcal::sim_wenglor
