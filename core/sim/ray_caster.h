// Ray casting against a Scene with Embree 3 (single precision, watertight triangles, exact
// spheres). Thread-safe after construction: many threads may cast at once.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <memory>

#include "core/sim/scene.h"
#include "core/util/expected.h"

namespace selfcal::sim {

class RayCaster {
 public:
  static Expected<std::unique_ptr<RayCaster>> Create(const Scene& scene);
  ~RayCaster();
  RayCaster(const RayCaster&) = delete;
  RayCaster& operator=(const RayCaster&) = delete;

  // Distance [m] along the unit `direction` from `origin` to the first surface, or +infinity
  // when nothing is hit within `max_distance`.
  double Cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
              double max_distance = std::numeric_limits<double>::infinity()) const;

  // The same cast, with the unit geometric normal of the surface hit (either side; zero and
  // distance +infinity on a miss) and its albedo (Scene::albedo; 1 for spheres): the field
  // effects need the angle of incidence and the reflectivity.
  struct Hit {
    double distance = std::numeric_limits<double>::infinity();
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    double albedo = 1;
  };
  Hit CastHit(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
              double max_distance = std::numeric_limits<double>::infinity()) const;

 private:
  struct Impl;
  explicit RayCaster(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace selfcal::sim
