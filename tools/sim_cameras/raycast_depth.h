// Depth maps from core/sim: a scene of the simulation testbed, ray cast with Embree from a camera
// pose, so that the simulated cameras serve what core/sim's sensors see. Computed once per frame
// size: the simulated camera stands still, as a depth camera does at a scan pose; the per-frame
// noise is added by the camera.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "core/sim/field_effects.h"
#include "core/sim/ray_caster.h"
#include "core/sim/scene.h"
#include "core/util/expected.h"
#include "tools/sim_cameras/depth_scene.h"

namespace selfcal::sim_cameras {

// Camera pose (x right, y down, z forward) at `eye` looking at `target`, with the scene's +z up in
// the image (up must not be parallel to the view direction).
Eigen::Isometry3d LookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                         const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ());

// Depth z [m] of pixel (u, v) of a pinhole camera at T_scene_camera: the first surface on the ray
// through the pixel centre, of the scene and of what moves in it (`moving`, when given: the
// walker, a moved box, the arm's links); 0 when nothing is hit within [closest, farthest] (as
// the analytic scene reports points outside the view range).
double RayCastDepth(const sim::RayCaster& caster, const Eigen::Isometry3d& T_scene_camera, double u,
                    double v, const PinholeIntrinsics& intrinsics, double closest_m,
                    double farthest_m, const sim::DynamicGeometry* moving = nullptr);

// RayCastDepth for every pixel, row-major.
std::vector<float> RayCastDepthMap(const sim::RayCaster& caster,
                                   const Eigen::Isometry3d& T_scene_camera, std::uint32_t width,
                                   std::uint32_t height, const PinholeIntrinsics& intrinsics,
                                   double closest_m, double farthest_m,
                                   const sim::DynamicGeometry* moving = nullptr);

// A named core/sim scene ("tabletop-teapot", "office", "lab", "corner") with a camera `distance_m`
// from the scene's focus, looking at it from above and from the robot's side (the base origin).
struct SimSceneView {
  sim::Scene scene;
  std::unique_ptr<sim::RayCaster> caster;
  Eigen::Isometry3d T_scene_camera = Eigen::Isometry3d::Identity();
};
Expected<SimSceneView> MakeSimSceneView(const std::string& name, double distance_m);

}  // namespace selfcal::sim_cameras
