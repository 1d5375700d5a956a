// Stage 4: nearest neighbours between datasets through k-d trees (the paper's "Point Matching")
// and stage 5, the rejection of matches (the paper's "Match Validation").
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "core/calib/calibrate.h"
#include "core/calib/projection.h"

namespace selfcal::calib {

// Matches of one dataset pair <i, j>, i < j: point_i[k] of Q_i has its nearest neighbour
// point_j[k] in Q_j. Indices are grid indices of the datasets.
struct PairMatches {
  std::uint32_t dataset_i = 0;
  std::uint32_t dataset_j = 0;
  std::vector<std::uint32_t> point_i;
  std::vector<std::uint32_t> point_j;

  std::size_t size() const { return point_i.size(); }
};

// A k-d tree (nanoflann) over a set of points, float structure-of-arrays. The points may be in
// any frame; the caller queries in the same frame.
class PointTree {
 public:
  // Builds over the points with keep[i] != 0; `x`, `y`, `z` are grid arrays of one dataset.
  PointTree(const std::vector<float>& x, const std::vector<float>& y, const std::vector<float>& z,
            const std::vector<std::uint8_t>& keep);
  ~PointTree();
  PointTree(const PointTree&) = delete;
  PointTree& operator=(const PointTree&) = delete;

  // The grid index of the nearest point within `max_distance` (strictly closer than it; infinity
  // = unbounded), or -1. `distance_squared` receives the squared distance.
  // `hint` (optional, in and out): a tree position, e.g. the previous query's answer. A search
  // starts with the hint's distance as its bound, which prunes far more when queries come in
  // grid order (neighbours match neighbours); the answer is the same (the hint wins only a tie).
  long Nearest(const Eigen::Vector3f& query, float max_distance, float& distance_squared,
               std::uint32_t* hint = nullptr) const;
  std::size_t size() const { return index_.size(); }

  // Access for nanoflann's adaptor interface.
  std::size_t kdtree_get_point_count() const { return index_.size(); }
  float kdtree_get_pt(std::size_t i, std::size_t dim) const {
    return dim == 0 ? x_[i] : (dim == 1 ? y_[i] : z_[i]);
  }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const {
    return false;
  }

 private:
  struct Index;
  std::vector<float> x_, y_, z_;
  std::vector<std::uint32_t> index_;  // tree position -> grid index
  std::unique_ptr<Index> tree_;
};

// Nearest neighbour in Q_j of every point of Q_i by exhaustive search (for tests).
long BruteForceNearest(const ProjectedCloud& cloud_j, const Eigen::Vector3f& query);

// An axis-aligned box of the kept points of a cloud.
struct Box {
  Eigen::Vector3f min = Eigen::Vector3f::Constant(std::numeric_limits<float>::infinity());
  Eigen::Vector3f max = Eigen::Vector3f::Constant(-std::numeric_limits<float>::infinity());
  bool Contains(const Eigen::Vector3f& p, float margin) const {
    return (p.array() >= min.array() - margin).all() && (p.array() <= max.array() + margin).all();
  }
  bool Overlaps(const Box& other, float margin) const {
    return (min.array() <= other.max.array() + margin).all() &&
           (other.min.array() <= max.array() + margin).all();
  }
};
Box KeptBox(const ProjectedCloud& cloud);

// The paper's match validation: removes matches with |q_i - q_j| > d_max or
// vn(q_i) . vn(q_j) < f_min (both in normalized units / cosines).
// reject_border (deviation 10): also drop a match whose point_j is on the border of Q_j
// (cloud_j.boundary, filled by the noise/edge filter stage).
void RejectMatches(const ProjectedCloud& cloud_i, const ProjectedCloud& cloud_j, double d_max,
                   double f_min, PairMatches& matches, bool reject_border = false);

// The unit normal of match <q_i = cloud_i[u], q_j = cloud_j[v]>'s residual (q_i - q_j) . n, in the
// clouds' frame: n(q_i), n(q_j), or their normalized sum (CostKind). Rejection (f_min > -1 keeps
// the two on one side) leaves the sum non-zero; should they cancel, n(q_i) is used.
Eigen::Vector3f MatchNormal(CostKind cost, const ProjectedCloud& cloud_i, std::uint32_t u,
                            const ProjectedCloud& cloud_j, std::uint32_t v);

}  // namespace selfcal::calib
