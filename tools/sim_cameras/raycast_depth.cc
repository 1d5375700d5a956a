#include "tools/sim_cameras/raycast_depth.h"

#include <algorithm>
#include <cmath>
#include <thread>

namespace selfcal::sim_cameras {

Eigen::Isometry3d LookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                         const Eigen::Vector3d& up) {
  const Eigen::Vector3d z = (target - eye).normalized();
  const Eigen::Vector3d x = z.cross(up).normalized();  // right: forward x up
  const Eigen::Vector3d y = z.cross(x);                // down
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = y;
  T.linear().col(2) = z;
  T.translation() = eye;
  return T;
}

double RayCastDepth(const sim::RayCaster& caster, const Eigen::Isometry3d& T_scene_camera, double u,
                    double v, const PinholeIntrinsics& intrinsics, double closest_m,
                    double farthest_m, const sim::DynamicGeometry* moving) {
  const Eigen::Vector3d ray = intrinsics.Unproject(u, v, 1.0);
  const double length = ray.norm();
  // Along the unit ray, depth z = distance / length; look a little beyond the far limit.
  const Eigen::Vector3d direction = T_scene_camera.linear() * (ray / length);
  const double limit = 1.01 * farthest_m * length;
  double distance = caster.Cast(T_scene_camera.translation(), direction, limit);
  if (moving != nullptr) {
    distance =
        std::min(distance, moving->Cast(T_scene_camera.translation(), direction, limit, nullptr));
  }
  if (!std::isfinite(distance)) return 0.0;
  const double z = distance / length;
  return z >= closest_m && z <= farthest_m ? z : 0.0;
}

std::vector<float> RayCastDepthMap(const sim::RayCaster& caster,
                                   const Eigen::Isometry3d& T_scene_camera, std::uint32_t width,
                                   std::uint32_t height, const PinholeIntrinsics& intrinsics,
                                   double closest_m, double farthest_m,
                                   const sim::DynamicGeometry* moving) {
  std::vector<float> depth(static_cast<std::size_t>(width) * height, 0.0f);
  // The caster is thread-safe: rows split over the cores (about 1 M rays for a PhotoNeo frame).
  const unsigned threads = std::max(1u, std::min(8u, std::thread::hardware_concurrency()));
  std::vector<std::thread> workers;
  for (unsigned t = 0; t < threads; ++t) {
    workers.emplace_back([&, t] {
      for (std::uint32_t v = t; v < height; v += threads) {
        for (std::uint32_t u = 0; u < width; ++u) {
          depth[static_cast<std::size_t>(v) * width + u] = static_cast<float>(RayCastDepth(
              caster, T_scene_camera, u, v, intrinsics, closest_m, farthest_m, moving));
        }
      }
    });
  }
  for (auto& w : workers) w.join();
  return depth;
}

Expected<SimSceneView> MakeSimSceneView(const std::string& name, double distance_m) {
  sim::SceneSpec spec;
  if (name == "tabletop-teapot") {
    spec.kind = sim::SceneSpec::Kind::kTabletop;
    spec.object = sim::SceneSpec::Object::kTeapot;
  } else if (name == "office") {
    spec.kind = sim::SceneSpec::Kind::kOffice;
  } else if (name == "lab") {
    spec.kind = sim::SceneSpec::Kind::kLab;
  } else if (name == "corner") {
    spec.kind = sim::SceneSpec::Kind::kCorner;
  } else {
    return Error{"unknown scene '" + name + "' (tabletop-teapot, office, lab, corner)"};
  }
  auto scene = sim::BuildScene(spec);
  if (!scene) return scene.error();
  SimSceneView view;
  view.scene = std::move(*scene);
  auto caster = sim::RayCaster::Create(view.scene);
  if (!caster) return caster.error();
  view.caster = std::move(*caster);
  // From the base's side and from above, 35 degrees down onto the focus.
  Eigen::Vector3d back(-view.scene.focus.x(), -view.scene.focus.y(), 0.0);
  back = back.norm() > 1e-6 ? back.normalized() : Eigen::Vector3d(-1, 0, 0);
  const double elevation = 35.0 * M_PI / 180.0;
  const Eigen::Vector3d eye =
      view.scene.focus +
      distance_m * (std::cos(elevation) * back + std::sin(elevation) * Eigen::Vector3d::UnitZ());
  view.T_scene_camera = LookAt(eye, view.scene.focus);
  return view;
}

}  // namespace selfcal::sim_cameras
