#include "tools/sim_cameras/scenario_camera.h"

#include <cmath>

#include "tools/sim_cameras/raycast_depth.h"

namespace selfcal::sim_cameras {

Expected<std::unique_ptr<ScenarioCamera>> ScenarioCamera::Create(const std::string& scenario_path,
                                                                 int view) {
  auto scenario = LoadDeviceScenario(scenario_path);
  if (!scenario) return scenario.error();
  if (scenario->setup.sensor.kind != SensorLayout::kDepthCamera) {
    return Error{scenario_path + ": key 'sensor' must name a depth camera"};
  }
  auto scan = DeviceScenarioScan(*scenario, view);
  if (!scan) return Error{scenario_path + ": " + scan.error().message};
  std::unique_ptr<ScenarioCamera> camera(new ScenarioCamera());
  camera->scenario_ = std::move(*scenario);
  camera->view_ = view;
  camera->joints_ = scan->start;
  camera->T_base_camera_ = camera->scenario_.frames->SensorPose(camera->joints_);
  const sim::FieldEffects& effects = camera->scenario_.frames->effects();
  if (effects.backlash.enabled || effects.thermal_growth.enabled) {
    // Where the arm stands in the middle of the scan, after the moves that brought it there.
    auto pose = DeviceScenarioSensorPose(camera->scenario_, view, 0.5);
    if (!pose) return Error{scenario_path + ": " + pose.error().message};
    camera->T_base_camera_ = *pose;
  }
  return camera;
}

std::vector<float> ScenarioCamera::IdealDepth(std::uint32_t width, std::uint32_t height,
                                              const PinholeIntrinsics& intrinsics) const {
  const sim::DynamicGeometry moving = scenario_.frames->Moving(joints_, view_, 0.5);
  return RayCastDepthMap(*scenario_.caster, T_base_camera_, width, height, intrinsics,
                         sensor().range_min, sensor().range_max, &moving);
}

void ScenarioCamera::FieldDepth(std::uint64_t frame, double device_time, std::uint32_t width,
                                std::uint32_t height, const PinholeIntrinsics& intrinsics,
                                std::vector<float>& depth) {
  const sim::DeviceFrameCaster& frames = *scenario_.frames;
  if (width != cells_width_ || height != cells_height_) {
    // The rays the camera really casts: its true focal lengths (the intrinsics effect).
    PinholeIntrinsics true_intrinsics = intrinsics;
    true_intrinsics.fx *= frames.FocalFactor();
    true_intrinsics.fy *= frames.FocalFactor();
    std::vector<Eigen::Vector3d> rays(static_cast<std::size_t>(width) * height);
    for (std::uint32_t v = 0; v < height; ++v) {
      for (std::uint32_t u = 0; u < width; ++u) {
        rays[static_cast<std::size_t>(v) * width + u] = true_intrinsics.Unproject(u, v, 1.0);
      }
    }
    // The walker stands where it is halfway through its walk during this view.
    cells_ = frames.Cast(rays, static_cast<int>(width), T_base_camera_,
                         frames.Moving(joints_, view_, 0.5));
    cells_width_ = width;
    cells_height_ = height;
  }
  const std::vector<double> measures =
      frames.Measure(cells_, static_cast<int>(width), static_cast<int>(height), device_time, frame);
  depth.resize(measures.size());
  for (std::size_t i = 0; i < measures.size(); ++i) {
    depth[i] = std::isfinite(measures[i]) ? static_cast<float>(measures[i]) : 0.0f;
  }
}

}  // namespace selfcal::sim_cameras
