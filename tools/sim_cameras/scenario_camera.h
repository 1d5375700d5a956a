// A depth camera of a simulation scenario, for the simulated cameras (the fake GigE Vision
// camera's --scenario, the OpenNI2 plugin's scenario= URI): the camera sits on the scenario's
// true arm at the start of scan `view` of its plan and looks into the scenario's scene. Without an
// `effects:` section it serves the ideal ray casts (the camera adds its own noise, as for a named
// scene); with one, the frames of core/sim/device_frame.h: the sensor file's noise and the effects
// a device can show, as selfcal-sim-scip serves them, and the walker (halfway through its walk)
// and the moved box of scan `view`; with backlash or thermal growth, from where `selfcal
// simulate`'s arm stands in the middle of that scan (DeviceScenarioSensorPose).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/camera/pinhole_intrinsics.h"
#include "core/util/expected.h"
#include "protocols/scenario/device_scenario.h"

namespace selfcal::sim_cameras {

class ScenarioCamera {
 public:
  static Expected<std::unique_ptr<ScenarioCamera>> Create(const std::string& scenario_path,
                                                          int view);

  // The scenario's sensor file: resolution, intrinsics, view range, noise.
  const sim::SensorModel& sensor() const { return scenario_.setup.sensor; }
  // True when the scenario has effects: serve FieldDepth, not IdealDepth plus noise.
  bool field() const { return scenario_.field; }
  const Eigen::Isometry3d& T_base_camera() const { return T_base_camera_; }
  const std::vector<double>& joints() const { return joints_; }

  // Depth z [m] per pixel (row-major, 0 = nothing within the sensor's view range) of a `width` x
  // `height` frame through `intrinsics`: the ray casts without noise, of the scene and of what
  // FieldDepth sees move in it (the arm's links, the walker, the moved box).
  std::vector<float> IdealDepth(std::uint32_t width, std::uint32_t height,
                                const PinholeIntrinsics& intrinsics) const;
  // The field frame `frame` at `device_time` [s on the camera's clock], noise included, in the
  // same layout. The ray casts are made once per frame size (the camera and the arm stand still).
  void FieldDepth(std::uint64_t frame, double device_time, std::uint32_t width,
                  std::uint32_t height, const PinholeIntrinsics& intrinsics,
                  std::vector<float>& depth);

 private:
  ScenarioCamera() = default;

  DeviceScenario scenario_;
  int view_ = 0;
  std::vector<double> joints_;
  Eigen::Isometry3d T_base_camera_ = Eigen::Isometry3d::Identity();
  sim::CellReturns cells_;  // pass 1 of the current frame size
  std::uint32_t cells_width_ = 0, cells_height_ = 0;
};

}  // namespace selfcal::sim_cameras
