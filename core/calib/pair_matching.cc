#include "core/calib/pair_matching.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/calib/edge_filter.h"
#include "core/calib/flying_pixels.h"
#include "core/calib/link_mask.h"
#include "core/calib/normals.h"
#include "core/calib/parallel.h"
#include "core/util/release.h"

namespace selfcal::calib {
namespace {

// The projected points a mask removes (1) become no measurement.
void Invalidate(const std::vector<std::uint8_t>& removed, ProjectedCloud& cloud) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 0; i < removed.size(); ++i) {
    if (removed[i]) cloud.x[i] = cloud.y[i] = cloud.z[i] = nan;
  }
}

}  // namespace

PairMatcher::PairMatcher(const std::vector<Dataset>& datasets, const Chain& chain,
                         const std::vector<PoseKnots>& knots, const CalibrationOptions& options,
                         int threads)
    : datasets_(datasets), chain_(chain), knots_(knots), options_(options), threads_(threads) {
  clouds_.resize(datasets.size());
  fixed_keep_.resize(datasets.size());
  fixed_boundary_.resize(datasets.size());
  flying_.resize(datasets.size());
  on_links_.resize(datasets.size());
  sensor_trees_.resize(datasets.size());
  base_trees_.resize(datasets.size());
  boxes_.resize(datasets.size());
  base_to_sensor_.resize(datasets.size());
}

PairMatcher::~PairMatcher() = default;

void PairMatcher::Prepare(const std::vector<double>& k_hat) {
  PrepareDatasets(k_hat, std::vector<bool>(datasets_.size(), true));
}

void PairMatcher::Prepare(const std::vector<double>& k_hat, const std::vector<DatasetPair>& pairs) {
  std::vector<bool> matched(datasets_.size(), false);
  for (const auto& [i, j] : pairs) matched[i] = matched[j] = true;
  PrepareDatasets(k_hat, matched);
}

void PairMatcher::PrepareDatasets(const std::vector<double>& k_hat,
                                  const std::vector<bool>& which) {
  const bool fast = options_.search == SearchStrategy::kFast;
  ParallelFor(datasets_.size(), threads_, [&](std::size_t d) {
    const Dataset& dataset = datasets_[d];
    ProjectedCloud& cloud = clouds_[d];
    if (!which[d]) {
      cloud = ProjectedCloud();
      base_trees_[d].reset();
      return;
    }
    cloud = ProjectDataset(dataset, chain_, k_hat.data(), fast ? &knots_[d] : nullptr);
    RemoveFlyingPixels(d, cloud);
    RemovePointsOnLinks(d, cloud, k_hat);
    if (options_.normals == NormalKind::kFit) {
      ComputeFittedNormals(dataset, cloud, options_.filter_n, options_.filter_m);
    } else {
      ComputeNormals(dataset, cloud);
    }
    const bool rigid = fast && dataset.layout == PoseLayout::kOnePerScan;
    if (rigid && !fixed_keep_[d].empty()) {
      cloud.keep = fixed_keep_[d];
      cloud.boundary = fixed_boundary_[d];
    } else {
      FilterNoiseAndEdges(cloud, options_.filter_n, options_.filter_m, options_.g_min);
      if (options_.surface_border) {
        // A step neither the surface nor the noise makes between neighbours: d_max / 2, three
        // sample spacings (a surface at 70 degrees to the view) and 5 sigma of the difference of
        // two measurements (sigma = sigma_abs + sigma_rel * range, the sensor file's noise).
        constexpr double kSigmas = 5.0 * 1.41421356;
        const SurfaceStep step{
            static_cast<float>((0.5 * options_.d_max + kSigmas * options_.sigma_abs) /
                               chain_.scale),
            static_cast<float>(kSigmas * options_.sigma_rel), 3.0f};
        MarkSurfaceBoundary(dataset, cloud, options_.filter_n + 1, options_.filter_m + 1, step);
      }
    }
    boxes_[d] = KeptBox(cloud);
    if (rigid) {
      double joints[kMaxJoints];
      const Transform3<double> T_base_sensor = chain_.Pose(k_hat.data(), dataset.Joints(0, joints));
      base_to_sensor_[d] = T_base_sensor.inverse().matrix().topRows<3>().cast<float>();
      if (fixed_keep_[d].empty()) {
        fixed_keep_[d] = cloud.keep;
        fixed_boundary_[d] = cloud.boundary;
        // Sensor-frame points in normalized units, built once.
        std::vector<float> x(dataset.x.size()), y(dataset.y.size()), z(dataset.z.size());
        const float inverse_scale = static_cast<float>(1.0 / chain_.scale);
        for (std::size_t i = 0; i < x.size(); ++i) {
          x[i] = dataset.x[i] * inverse_scale;
          y[i] = dataset.y[i] * inverse_scale;
          z[i] = dataset.z[i] * inverse_scale;
        }
        sensor_trees_[d] = std::make_unique<PointTree>(x, y, z, cloud.keep);
      }
    } else {
      base_trees_[d] = std::make_unique<PointTree>(cloud.x, cloud.y, cloud.z, cloud.keep);
    }
  });
}

void PairMatcher::RemoveFlyingPixels(std::size_t d, ProjectedCloud& cloud) {
  if (!(options_.flying_pixel_angle_deg > 0)) return;
  std::vector<std::uint8_t>& flying = flying_[d];
  if (flying.empty()) {
    const FlyingPixelRule rule{options_.flying_pixel_angle_deg * M_PI / 180.0, options_.sigma_abs,
                               options_.sigma_rel};
    flying = FlyingPixels(datasets_[d], rule);
  }
  Invalidate(flying, cloud);
}

void PairMatcher::RemovePointsOnLinks(std::size_t d, ProjectedCloud& cloud,
                                      const std::vector<double>& k_hat) {
  if (!(chain_.link_radius > 0)) return;
  std::vector<std::uint8_t>& on_links = on_links_[d];
  if (on_links.empty()) {
    const double radius = chain_.link_radius + options_.link_margin_m / chain_.scale;
    on_links = PointsOnLinks(datasets_[d], cloud, chain_, k_hat.data(), radius);
  }
  Invalidate(on_links, cloud);
}

std::size_t PairMatcher::PointsOnLinksCount() const {
  std::size_t count = 0;
  for (const auto& on_links : on_links_) {
    for (std::uint8_t on_link : on_links) count += on_link;
  }
  return count;
}

std::vector<ProjectedCloud> PairMatcher::TakeClouds() {
  std::vector<ProjectedCloud> taken = std::move(clouds_);
  clouds_.assign(datasets_.size(), ProjectedCloud());
  return taken;
}

void PairMatcher::ReleaseBaseTrees() {
  for (auto& tree : base_trees_) tree.reset();
}

void PairMatcher::KeepOnlyNormals() {
  ReleaseBaseTrees();
  for (ProjectedCloud& cloud : clouds_) {
    Release(cloud.x), Release(cloud.y), Release(cloud.z);
    Release(cloud.keep), Release(cloud.boundary);
    Release(cloud.origin), Release(cloud.knot_origin);
    cloud.knots = nullptr;  // no origins left to blend: PoseCount() is 0, not the knots' poses
  }
}

void PairMatcher::PointsMoved() {
  for (auto& flying : flying_) flying.clear();
  for (auto& keep : fixed_keep_) keep.clear();
  for (auto& boundary : fixed_boundary_) boundary.clear();
}

PairMatches PairMatcher::MatchPair(const DatasetPair& pair) const {
  const bool fast = options_.search == SearchStrategy::kFast;
  const double d_max_hat = options_.d_max / chain_.scale;
  const float radius =
      fast ? static_cast<float>(d_max_hat) : std::numeric_limits<float>::infinity();
  const auto [i, j] = pair;
  PairMatches matches;
  matches.dataset_i = i;
  matches.dataset_j = j;
  const ProjectedCloud& cloud_i = clouds_[i];
  const ProjectedCloud& cloud_j = clouds_[j];
  const float margin = static_cast<float>(d_max_hat);
  if (fast && !boxes_[i].Overlaps(boxes_[j], margin)) return matches;
  const PointTree* sensor_tree = fast ? sensor_trees_[j].get() : nullptr;
  const PointTree* tree = sensor_tree != nullptr ? sensor_tree : base_trees_[j].get();
  std::uint32_t hint = std::numeric_limits<std::uint32_t>::max();  // fast: the previous answer
  const std::size_t stride = static_cast<std::size_t>(options_.query_stride);  // >= 1: IsValid
  for (std::size_t u = 0; u < cloud_i.keep.size(); ++u) {
    if (!cloud_i.keep[u]) continue;
    if (stride > 1 && ((u / cloud_i.cols) % stride != 0 || (u % cloud_i.cols) % stride != 0))
      continue;
    Eigen::Vector3f query = cloud_i.Point(u);
    if (fast && !boxes_[j].Contains(query, margin)) continue;
    if (sensor_tree != nullptr)
      query = base_to_sensor_[j].leftCols<3>() * query + base_to_sensor_[j].col(3);
    float distance_squared = 0;
    const long v = tree->Nearest(query, radius, distance_squared, fast ? &hint : nullptr);
    if (v < 0) continue;
    matches.point_i.push_back(static_cast<std::uint32_t>(u));
    matches.point_j.push_back(static_cast<std::uint32_t>(v));
  }
  RejectMatches(cloud_i, cloud_j, d_max_hat, options_.f_min, matches,
                options_.reject_coverage_border);
  // The caller keeps every pair's matches until all are made: not the candidates' capacity.
  matches.point_i.shrink_to_fit();
  matches.point_j.shrink_to_fit();
  return matches;
}

std::vector<DatasetPair> AllPairs(const std::vector<bool>& use) {
  std::vector<DatasetPair> pairs;
  for (std::uint32_t i = 0; i < use.size(); ++i) {
    if (!use[i]) continue;
    for (std::uint32_t j = i + 1; j < use.size(); ++j) {
      if (use[j]) pairs.emplace_back(i, j);
    }
  }
  return pairs;
}

std::vector<DatasetPair> PairsTouching(const std::vector<bool>& validation) {
  std::vector<DatasetPair> pairs;
  for (std::uint32_t i = 0; i < validation.size(); ++i) {
    for (std::uint32_t j = i + 1; j < validation.size(); ++j) {
      if (validation[i] || validation[j]) pairs.emplace_back(i, j);
    }
  }
  return pairs;
}

}  // namespace selfcal::calib
