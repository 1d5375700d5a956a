// A real site's map from the scans of an earlier session, fused in the base frame
// (protocols/report/fused_cloud.h), in the form the planner needs to predict what new views will
// see: surfaces the ray caster can hit, and the space the points fill, which the sensor and the
// arm's links must keep clear of. A fused cloud is all a site has; no mesh of it exists.
//
// Surfaces are splats: one square per voxel that holds enough points, through the points' mean
// and perpendicular to the least-variance direction of the points around it, twice the voxel's
// width so that neighbouring squares overlap and rays do not slip between them. Their normals
// follow the surface (an axis-aligned voxel mesh would turn it into steps), and the information
// a view gets from a surface depends on its normals.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <span>

#include "core/sim/mesh.h"
#include "core/sim/occupancy.h"
#include "core/sim/scene.h"

namespace selfcal::sim {

struct SiteMapOptions {
  double surface_voxel_m = 0.02;    // the splats' spacing
  double occupancy_voxel_m = 0.05;  // the free-space grid's
  // A voxel with fewer points is taken for noise (a flying pixel, a passer-by's few returns).
  int min_points = 3;
};

struct SiteMap {
  TriangleMesh surfaces;  // two triangles per splat
  Occupancy occupied;
  std::size_t points = 0;  // finite points read
  std::size_t splats = 0;
};

// The map of `points` (base frame, m); non-finite points are skipped.
SiteMap BuildSiteMap(std::span<const Eigen::Vector3f> points, const SiteMapOptions& options);

// The map becomes the scene's surfaces (part "map"; what the scene had is dropped) and its
// occupied space; the scene's workspace, obstacles and focus stay.
void UseSiteMap(SiteMap map, Scene& scene);

}  // namespace selfcal::sim
