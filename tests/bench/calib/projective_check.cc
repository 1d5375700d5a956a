// Projective association against the k-d tree: for every pair of fit scans taken in one pose
// each (depth camera), every kept point of the first looks for its nearest neighbour in the
// second's kept points both ways (ProjectiveIndex, and the engine's sensor-frame tree bounded by
// d_max), at MODEL (a simulation's truth: the scans where the engine ends). Prints how often they
// agree, where they differ how far apart in the image their answers lie, and the time of each
// on one thread. Never run by ctest.
//
// Usage: projective_check MODEL.yaml SENSOR.yaml RECORDING.lcmlog [FIT_SCANS]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "core/calib/matching.h"
#include "core/calib/pair_matching.h"
#include "core/calib/projective_index.h"
#include "tests/bench/calib/bench_recording.h"

namespace {

using namespace selfcal;
using namespace selfcal::calib;

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct Agreement {
  std::size_t queries = 0, same = 0, other = 0, tree_only = 0, projective_only = 0;
  std::size_t far_in_image = 0;  // other: the answers more than the window apart
  double tree_seconds = 0, projective_seconds = 0;
};

void Compare(const ProjectedCloud& from, const Dataset& to, const std::vector<std::uint8_t>& keep,
             const Eigen::Matrix<float, 3, 4>& base_to_sensor, double scale, float max_distance,
             Agreement& agreement) {
  std::vector<float> x(to.x.size()), y(to.y.size()), z(to.z.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    x[i] = static_cast<float>(to.x[i] / scale);
    y[i] = static_cast<float>(to.y[i] / scale);
    z[i] = static_cast<float>(to.z[i] / scale);
  }
  const PointTree tree(x, y, z, keep);
  const ProjectiveIndex projective(to.rows, to.cols, x, y, z, keep);
  std::vector<Eigen::Vector3f> queries;
  for (std::size_t i = 0; i < from.keep.size(); ++i) {
    if (from.keep[i])
      queries.push_back(base_to_sensor.leftCols<3>() * from.Point(i) + base_to_sensor.col(3));
  }
  std::vector<long> by_tree(queries.size()), by_projection(queries.size());
  float distance_squared = 0;
  std::uint32_t hint = 0;
  auto start = std::chrono::steady_clock::now();
  for (std::size_t q = 0; q < queries.size(); ++q)
    by_tree[q] = tree.Nearest(queries[q], max_distance, distance_squared, &hint);
  agreement.tree_seconds += SecondsSince(start);
  start = std::chrono::steady_clock::now();
  for (std::size_t q = 0; q < queries.size(); ++q)
    by_projection[q] = projective.Nearest(queries[q], max_distance, distance_squared);
  agreement.projective_seconds += SecondsSince(start);
  const long cols = static_cast<long>(to.cols);
  for (std::size_t q = 0; q < queries.size(); ++q) {
    const long a = by_tree[q], b = by_projection[q];
    ++agreement.queries;
    if (a < 0 && b < 0) continue;
    if (a == b) {
      ++agreement.same;
    } else if (b < 0) {
      ++agreement.tree_only;
    } else if (a < 0) {
      ++agreement.projective_only;
    } else {
      ++agreement.other;
      const long apart = std::max(std::abs(a / cols - b / cols), std::abs(a % cols - b % cols));
      agreement.far_in_image += apart > ProjectiveIndex::kWindowRadius ? 1 : 0;
    }
  }
}

int Run(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s MODEL.yaml SENSOR.yaml RECORDING.lcmlog [FIT_SCANS]\n",
                 argv[0]);
    return 2;
  }
  auto loaded = bench::LoadBenchRecording(argv[1], argv[2], argv[3], argc > 4 ? argv[4] : nullptr);
  if (!loaded) return 1;
  const std::vector<Dataset>& datasets = loaded->datasets;
  const bench::EngineStart start = bench::StartEngine(*loaded, 1);
  PairMatcher matcher(datasets, start.chain, start.knots, loaded->options, 1);
  matcher.Prepare(start.k_hat);
  const float max_distance = static_cast<float>(loaded->options.d_max / start.scale);
  Agreement agreement;
  for (const DatasetPair& pair : AllPairs(start.fit)) {
    const Dataset& to = datasets[pair.second];
    if (to.layout != PoseLayout::kOnePerScan) continue;
    double joints[kMaxJoints];
    const Eigen::Matrix<float, 3, 4> base_to_sensor =
        start.chain.Pose(start.k_hat.data(), to.Joints(0, joints))
            .inverse()
            .matrix()
            .topRows<3>()
            .cast<float>();
    Compare(matcher.clouds()[pair.first], to, matcher.clouds()[pair.second].keep, base_to_sensor,
            start.scale, max_distance, agreement);
  }
  const auto share = [&](std::size_t n) {
    return 100.0 * static_cast<double>(n) / static_cast<double>(agreement.queries);
  };
  std::printf(
      "queries %zu: the same answer %.2f %%, another %.2f %% (%.2f %% more than %d pixels from "
      "the tree's), only the tree %.2f %%, only the projection %.2f %%\n"
      "one query: tree %.0f ns, projection %.0f ns (1 thread)\n",
      agreement.queries, share(agreement.same), share(agreement.other),
      share(agreement.far_in_image), ProjectiveIndex::kWindowRadius, share(agreement.tree_only),
      share(agreement.projective_only),
      1e9 * agreement.tree_seconds / static_cast<double>(agreement.queries),
      1e9 * agreement.projective_seconds / static_cast<double>(agreement.queries));
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return Run(argc, argv); }
