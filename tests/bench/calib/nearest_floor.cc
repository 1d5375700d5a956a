// The floor of matching: what one nearest-neighbour query per point per ICP iteration costs on
// this machine, next to what the engine's matching of every fit pair costs, both on one thread.
// The recording is projected at MODEL (a simulation's truth: the scans where the engine ends);
// each fit scan's kept points query the k-d tree of the next fit scan (base frame, bounded by
// d_max, the previous answer as the hint, as the engine's search), which gives the time of one
// query; the floor is that time times the fit scans' kept points. Never run by ctest.
//
// Usage: nearest_floor MODEL.yaml SENSOR.yaml RECORDING.lcmlog [FIT_SCANS]
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "core/calib/chain.h"
#include "core/calib/matching.h"
#include "core/calib/pair_information.h"
#include "core/calib/pair_matching.h"
#include "core/calib/pose_knots.h"
#include "core/calib/projection.h"
#include "core/model/normalization.h"
#include "protocols/model_file/model_file.h"
#include "tests/bench/calib/bench_recording.h"

namespace {

using namespace selfcal;
using namespace selfcal::calib;

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct QueryTiming {
  std::size_t queries = 0, found = 0;
  double seconds = 0;
};

// Every kept point of `from` queries `tree` (one thread, in grid order, hint warm).
void QueryAll(const ProjectedCloud& from, const PointTree& tree, float max_distance,
              QueryTiming& timing) {
  std::uint32_t hint = 0;
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < from.keep.size(); ++i) {
    if (!from.keep[i]) continue;
    float distance_squared = 0;
    const Eigen::Vector3f query(from.x[i], from.y[i], from.z[i]);
    timing.found += tree.Nearest(query, max_distance, distance_squared, &hint) >= 0;
    ++timing.queries;
  }
  timing.seconds += SecondsSince(start);
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
  const CalibrationOptions& options = loaded->options;

  const bench::EngineStart start = bench::StartEngine(*loaded, 1);
  const double scale = start.scale;
  const std::vector<bool>& fit = start.fit;
  PairMatcher matcher(datasets, start.chain, start.knots, options, 1);
  matcher.Prepare(start.k_hat);
  const std::vector<ProjectedCloud>& clouds = matcher.clouds();

  // The engine: every fit pair matched and rejected, as one ICP iteration does.
  const std::vector<DatasetPair> pairs = AllPairs(fit);
  std::size_t matches = 0;
  const auto engine_start = std::chrono::steady_clock::now();
  for (const DatasetPair& pair : pairs) matches += matcher.MatchPair(pair).size();
  const double engine_seconds = SecondsSince(engine_start);

  // The floor: one query per kept point of every fit scan, into the next fit scan's tree.
  std::vector<std::size_t> fit_scans;
  for (std::size_t d = 0; d < fit.size(); ++d) {
    if (fit[d]) fit_scans.push_back(d);
  }
  const float max_distance = static_cast<float>(options.d_max / scale);
  QueryTiming timing;
  for (std::size_t f = 0; f < fit_scans.size(); ++f) {
    const ProjectedCloud& next = clouds[fit_scans[(f + 1) % fit_scans.size()]];
    const PointTree tree(next.x, next.y, next.z, next.keep);
    QueryAll(clouds[fit_scans[f]], tree, max_distance, timing);
  }
  const double per_query = timing.seconds / static_cast<double>(timing.queries);
  const double floor = timing.seconds;
  std::printf(
      "fit scans %zu, pairs %zu, kept points %zu (%.0f %% found a neighbour within d_max)\n"
      "one query: %.0f ns; floor, one query per kept point: %.3f s per iteration (1 thread)\n"
      "engine, every fit pair matched and rejected: %.3f s per iteration (1 thread), %zu "
      "matches; ratio to the floor %.1f\n",
      fit_scans.size(), pairs.size(), timing.queries,
      100.0 * static_cast<double>(timing.found) / static_cast<double>(timing.queries),
      per_query * 1e9, floor, engine_seconds, matches, engine_seconds / floor);
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return Run(argc, argv); }
