// One ICP iteration's data association: project every dataset, compute normals, filter noise and
// edges, then match every pair <i, j> (i < j) of the chosen datasets and reject bad matches.
// The two search strategies (CalibrationOptions::search) differ only in how they search, never in
// what they accept:
//  - reference: every point projected along the full chain, a k-d tree over Q_j in the base
//    frame, rebuilt every iteration, unbounded nearest-neighbour search, then rejection (the
//    paper's way);
//  - fast: points projected through their scan's pose knots (pose_knots.h); a scan taken in one
//    pose (depth camera) is rigid, so its tree lives in its sensor frame and is built once (again
//    when the intrinsics' correction moves the points); other
//    trees are rebuilt in the base frame. Searches are bounded by d_max (a farther neighbour is
//    rejected anyway) and pairs whose boxes, grown by d_max, do not overlap are skipped. Both are
//    exact: they only skip matches that rejection would remove.
#pragma once

#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "core/calib/calibrate.h"
#include "core/calib/chain.h"
#include "core/calib/matching.h"
#include "core/calib/pose_knots.h"
#include "core/calib/projection.h"

namespace selfcal::calib {

using DatasetPair = std::pair<std::uint32_t, std::uint32_t>;

class PairMatcher {
 public:
  // `knots`: one per dataset; the fast search projects through them (pose_knots.h).
  PairMatcher(const std::vector<Dataset>& datasets, const Chain& chain,
              const std::vector<PoseKnots>& knots, const CalibrationOptions& options, int threads);
  ~PairMatcher();

  // Projection (without the flying pixels, flying_pixels.h, and the points on the arm's links,
  // link_mask.h), normals and the noise/edge filter
  // of every dataset at k_hat.
  // With the fast search, the filter result of a single-pose dataset (and the border of its
  // coverage) is computed once and kept until PointsMoved(): it is invariant under a rigid
  // motion (normals rotate together).
  void Prepare(const std::vector<double>& k_hat);
  // The same for only the datasets that `pairs` match; the others' clouds and trees are freed
  // (the fit loop does not project the validation scans).
  void Prepare(const std::vector<double>& k_hat, const std::vector<DatasetPair>& pairs);
  // The datasets' points changed (the sensor intrinsics' correction, sensor_intrinsics.h): the
  // next Prepare() filters every scan again and rebuilds the sensor-frame trees.
  void PointsMoved();
  // Matches of one pair at the k_hat of the last Prepare(), after rejection. Thread-safe:
  // callers match pairs in parallel (MatchProblem::SetMatches).
  PairMatches MatchPair(const DatasetPair& pair) const;
  // Frees the base-frame trees until the next Prepare() builds them again (a LiDAR's 9 bytes a
  // point).
  void ReleaseBaseTrees();
  // Frees what only matching reads, until the next Prepare() makes it again: the base-frame
  // trees and the clouds' points, filter marks and origins (a LiDAR's 23 bytes a point). The
  // normals stay: the solve that follows matching reads them (MatchNormal).
  void KeepOnlyNormals();
  // The query stride of the next MatchPair calls (the options' query_stride until then; >= 1):
  // the coarse-to-fine loop's levels.
  void SetQueryStride(int stride) { options_.query_stride = stride; }

  const std::vector<ProjectedCloud>& clouds() const { return clouds_; }
  // Moves the clouds out (for their last reader); the next Prepare() makes them again.
  std::vector<ProjectedCloud> TakeClouds();
  // How many points the link mask removes from all datasets (0 before Prepare() or without it).
  std::size_t PointsOnLinksCount() const;

 private:
  // Prepare() of the datasets d with which[d]; the others' clouds and base trees are freed.
  void PrepareDatasets(const std::vector<double>& k_hat, const std::vector<bool>& which);
  // Invalidates the projected flying pixels of dataset d (computed on first use).
  void RemoveFlyingPixels(std::size_t d, ProjectedCloud& cloud);
  // Invalidates the points of dataset d on the arm's links (link_mask.h; computed on first use,
  // at that Prepare()'s k_hat).
  void RemovePointsOnLinks(std::size_t d, ProjectedCloud& cloud, const std::vector<double>& k_hat);

  const std::vector<Dataset>& datasets_;
  const Chain& chain_;
  const std::vector<PoseKnots>& knots_;
  CalibrationOptions options_;
  int threads_;
  std::vector<ProjectedCloud> clouds_;
  std::vector<std::vector<std::uint8_t>> fixed_keep_;      // fast: filter result of rigid scans
  std::vector<std::vector<std::uint8_t>> fixed_boundary_;  // ... and the border of its coverage
  std::vector<std::vector<std::uint8_t>> flying_;          // flying_pixels.h, once per points
  std::vector<std::vector<std::uint8_t>> on_links_;        // link_mask.h, once
  std::vector<std::unique_ptr<PointTree>> sensor_trees_;   // fast: rigid scans, sensor frame
  std::vector<std::unique_ptr<PointTree>> base_trees_;     // rebuilt per Prepare()
  std::vector<Box> boxes_;
  std::vector<Eigen::Matrix<float, 3, 4>> base_to_sensor_;  // rigid scans: T_sensor_base
};

// All pairs i < j of the datasets selected by `use`.
std::vector<DatasetPair> AllPairs(const std::vector<bool>& use);
// Pairs i < j where at least one of the two is selected by `validation` (for validation RMS).
std::vector<DatasetPair> PairsTouching(const std::vector<bool>& validation);

}  // namespace selfcal::calib
