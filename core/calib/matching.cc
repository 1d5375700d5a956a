#include "core/calib/matching.h"

#include <algorithm>
#include <nanoflann.hpp>

namespace selfcal::calib {

namespace {

// Keeps the single nearest point strictly closer than the initial radius: a distance-bounded
// search prunes every branch farther than that radius.
class NearestResult {
 public:
  using DistanceType = float;
  using IndexType = std::uint32_t;
  explicit NearestResult(float radius_squared) : worst_(radius_squared) {}
  // Starts from a known point at that distance: only strictly closer points replace it.
  NearestResult(float distance_squared, std::uint32_t index)
      : worst_(distance_squared), index_(index), found_(true) {}
  bool full() const { return found_; }
  bool addPoint(float distance, std::uint32_t index) {
    if (distance < worst_) {
      worst_ = distance;
      index_ = index;
      found_ = true;
    }
    return true;
  }
  float worstDist() const { return worst_; }
  bool found() const { return found_; }
  std::uint32_t index() const { return index_; }

 private:
  float worst_;
  std::uint32_t index_ = 0;
  bool found_ = false;
};

}  // namespace

struct PointTree::Index {
  using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, PointTree>,
                                                   PointTree, 3, std::uint32_t>;
  explicit Index(const PointTree& points)
      : tree(3, points, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {}
  Tree tree;
};

PointTree::PointTree(const std::vector<float>& x, const std::vector<float>& y,
                     const std::vector<float>& z, const std::vector<std::uint8_t>& keep) {
  // Sized once: grown by push_back, a LiDAR's trees held a third more than their points.
  const auto kept = static_cast<std::size_t>(
      std::count_if(keep.begin(), keep.end(), [](std::uint8_t k) { return k != 0; }));
  index_.reserve(kept);
  x_.reserve(kept), y_.reserve(kept), z_.reserve(kept);
  for (std::size_t i = 0; i < keep.size(); ++i) {
    if (!keep[i]) continue;
    index_.push_back(static_cast<std::uint32_t>(i));
    x_.push_back(x[i]);
    y_.push_back(y[i]);
    z_.push_back(z[i]);
  }
  tree_ = std::make_unique<Index>(*this);
}

PointTree::~PointTree() = default;

long PointTree::Nearest(const Eigen::Vector3f& query, float max_distance, float& distance_squared,
                        std::uint32_t* hint) const {
  if (index_.empty()) return -1;
  const float radius_squared = std::isinf(max_distance) ? std::numeric_limits<float>::infinity()
                                                        : max_distance * max_distance;
  NearestResult result(radius_squared);
  if (hint != nullptr && *hint < index_.size()) {
    const float dx = x_[*hint] - query.x(), dy = y_[*hint] - query.y(), dz = z_[*hint] - query.z();
    const float hint_squared = dx * dx + dy * dy + dz * dz;
    if (hint_squared < radius_squared) result = NearestResult(hint_squared, *hint);
  }
  const float point[3] = {query.x(), query.y(), query.z()};
  tree_->tree.findNeighbors(result, point, nanoflann::SearchParams(0, 0.0f, false));
  if (!result.found()) return -1;
  distance_squared = result.worstDist();
  if (hint != nullptr) *hint = result.index();
  return static_cast<long>(index_[result.index()]);
}

long BruteForceNearest(const ProjectedCloud& cloud_j, const Eigen::Vector3f& query) {
  long best = -1;
  float best_distance = std::numeric_limits<float>::infinity();
  for (std::size_t k = 0; k < cloud_j.keep.size(); ++k) {
    if (!cloud_j.keep[k]) continue;
    const float d = (cloud_j.Point(k) - query).squaredNorm();
    if (d < best_distance) {
      best_distance = d;
      best = static_cast<long>(k);
    }
  }
  return best;
}

Box KeptBox(const ProjectedCloud& cloud) {
  Box box;
  for (std::size_t i = 0; i < cloud.keep.size(); ++i) {
    if (!cloud.keep[i]) continue;
    box.min = box.min.cwiseMin(cloud.Point(i));
    box.max = box.max.cwiseMax(cloud.Point(i));
  }
  return box;
}

void RejectMatches(const ProjectedCloud& cloud_i, const ProjectedCloud& cloud_j, double d_max,
                   double f_min, PairMatches& matches, bool reject_border) {
  reject_border = reject_border && cloud_j.boundary.size() == cloud_j.keep.size();
  std::size_t kept = 0;
  for (std::size_t k = 0; k < matches.size(); ++k) {
    const std::uint32_t u = matches.point_i[k];
    const std::uint32_t v = matches.point_j[k];
    const double distance = static_cast<double>((cloud_i.Point(u) - cloud_j.Point(v)).norm());
    const double overlap = static_cast<double>(cloud_i.Normal(u).dot(cloud_j.Normal(v)));
    if (!(distance <= d_max) || !(overlap >= f_min)) continue;
    if (reject_border && cloud_j.boundary[v]) continue;
    matches.point_i[kept] = u;
    matches.point_j[kept] = v;
    ++kept;
  }
  matches.point_i.resize(kept);
  matches.point_j.resize(kept);
}

Eigen::Vector3f MatchNormal(CostKind cost, const ProjectedCloud& cloud_i, std::uint32_t u,
                            const ProjectedCloud& cloud_j, std::uint32_t v) {
  switch (cost) {
    case CostKind::kPaper:
      return cloud_i.Normal(u);
    case CostKind::kTarget:
      return cloud_j.Normal(v);
    case CostKind::kSymmetric: {
      const Eigen::Vector3f sum = cloud_i.Normal(u) + cloud_j.Normal(v);
      const float norm = sum.norm();
      return norm > 1e-6f ? Eigen::Vector3f(sum / norm) : cloud_i.Normal(u);
    }
  }
  return cloud_i.Normal(u);
}

}  // namespace selfcal::calib
