// The engine's cost at a given model (a simulation's truth): where its residuals come from.
// Runs the engine's own stages (projection, normals, noise/edge filter, matching, rejection:
// PairMatcher) on the fit pairs of a recording at the model, then prints the point-to-plane
// residuals of the matches split by match length and by where q_j lies (on the border of Q_j's
// coverage or inside), for each CostKind's normal: RMS, mean (signed: the residual's sign is
// n . (q_i - q_j) with n facing q_i's sensor, so a mean away from 0 is a bias) and the share of
// the squared sum. On a noise-free recording at the truth every residual is an error of the cost,
// not of the model. Never run by ctest.
//
// Usage: cost_at_truth MODEL.yaml SENSOR.yaml RECORDING.lcmlog [FIT_SCANS [exact|surface]]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "core/calib/calibrate.h"
#include "core/calib/chain.h"
#include "core/calib/edge_filter.h"
#include "core/calib/pair_information.h"
#include "core/calib/pair_matching.h"
#include "core/calib/point_to_plane.h"
#include "core/calib/pose_knots.h"
#include "core/calib/projection.h"
#include "core/model/evaluation.h"
#include "core/model/kinematics.h"
#include "core/model/normalization.h"
#include "protocols/model_file/model_file.h"
#include "tests/bench/calib/bench_recording.h"

namespace {

using namespace selfcal;
using namespace selfcal::calib;

struct Bucket {
  double sum[3] = {0, 0, 0}, squared[3] = {0, 0, 0};
  std::size_t count = 0;
  void Add(const double r[3]) {
    for (int c = 0; c < 3; ++c) {
      sum[c] += r[c];
      squared[c] += r[c] * r[c];
    }
    ++count;
  }
};

constexpr CostKind kCosts[3] = {CostKind::kPaper, CostKind::kTarget, CostKind::kSymmetric};

void Print(const char* name, const Bucket& bucket, const Bucket& total, double scale) {
  if (bucket.count == 0) return;
  std::printf("%-22s %9zu %6.2f%%", name, bucket.count,
              100.0 * static_cast<double>(bucket.count) / static_cast<double>(total.count));
  for (int c = 0; c < 3; ++c) {
    const double n = static_cast<double>(bucket.count);
    std::printf(" | %8.4f %8.4f %6.2f%%", std::sqrt(bucket.squared[c] / n) * scale * 1e3,
                bucket.sum[c] / n * scale * 1e3, 100.0 * bucket.squared[c] / total.squared[c]);
  }
  std::printf("\n");
}

int Run(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s MODEL.yaml SENSOR.yaml RECORDING.lcmlog [FIT_SCANS]\n",
                 argv[0]);
    return 2;
  }
  auto loaded = bench::LoadBenchRecording(argv[1], argv[2], argv[3], argc > 4 ? argv[4] : nullptr);
  if (!loaded) return 1;
  const RobotModel& model = loaded->model.model;
  const std::vector<Dataset>& datasets = loaded->datasets;
  CalibrationOptions options = loaded->options;
  // Every match is classified, none rejected for the border; "surface" takes the border of the
  // coverage surface over the filter window (MarkCoverageBoundary).
  options.reject_coverage_border = false;
  options.surface_border = argc > 5 && std::string(argv[5]) == "surface";

  const bench::EngineStart start = bench::StartEngine(*loaded, 2);
  const double scale = start.scale;
  const Chain& chain = start.chain;
  const std::vector<double>& k_hat = start.k_hat;
  const std::vector<PoseKnots>& knots = start.knots;
  const std::vector<bool>& fit = start.fit;
  PairMatcher matcher(datasets, chain, knots, options, 2);
  matcher.Prepare(k_hat);

  const double limits_mm[] = {0.5, 1, 2, 3, 5, 10, 20};
  const char* names[] = {"length <= 0.5 mm", "0.5 - 1 mm", "1 - 2 mm",  "2 - 3 mm",
                         "3 - 5 mm",         "5 - 10 mm",  "10 - 20 mm"};
  const double angle_limits_deg[] = {0.1, 1, 5, 15, 90};
  const char* angle_names[] = {"normals within 0.1 deg", "0.1 - 1 deg", "1 - 5 deg", "5 - 15 deg",
                               "15 - 37 deg"};
  const double ratio_limits[] = {0.5, 1.0, 1.5, 2.0, 3.0, 1e30};
  const char* ratio_names[] = {"lateral <= 0.5 spacing", "0.5 - 1 spacing", "1 - 1.5 spacing",
                               "1.5 - 2 spacing",        "2 - 3 spacing",   "> 3 spacing"};
  Bucket total, by_length[7], by_angle[5], by_ratio[6], border, inside;
  // The sample spacing of a cloud at point v: per grid direction the distance to the nearer
  // measured neighbour, the larger of the two directions.
  auto spacing = [](const ProjectedCloud& cloud, std::uint32_t v) {
    const long rows = static_cast<long>(cloud.rows), cols = static_cast<long>(cloud.cols);
    const long r = static_cast<long>(v) / cols, c = static_cast<long>(v) % cols;
    auto nearer = [&](long dr, long dc) {
      float best = std::numeric_limits<float>::infinity();
      for (int sign : {-1, 1}) {
        const long rr = r + sign * dr, cc = c + sign * dc;
        if (rr < 0 || rr >= rows || cc < 0 || cc >= cols) continue;
        const std::size_t k = static_cast<std::size_t>(rr * cols + cc);
        if (!cloud.Valid(k)) continue;
        best = std::min(best, (cloud.Point(k) - cloud.Point(v)).norm());
      }
      return best;
    };
    const float along_rows = nearer(1, 0), along_cols = nearer(0, 1);
    if (std::isinf(along_rows)) return along_cols;
    if (std::isinf(along_cols)) return along_rows;
    return std::max(along_rows, along_cols);
  };
  const std::vector<DatasetPair> pairs = AllPairs(fit);
  std::vector<PairMatches> all_matches;
  // Per match: its length bucket, its normal-angle bucket + 8, border + 16.
  std::vector<std::vector<std::uint8_t>> classes, ratio_class;
  for (const DatasetPair& pair : pairs) {
    all_matches.push_back(matcher.MatchPair(pair));
    const PairMatches& matches = all_matches.back();
    classes.emplace_back();
    ratio_class.emplace_back();
    const ProjectedCloud& cloud_i = matcher.clouds()[pair.first];
    const ProjectedCloud& cloud_j = matcher.clouds()[pair.second];
    for (std::size_t m = 0; m < matches.size(); ++m) {
      const std::uint32_t u = matches.point_i[m], v = matches.point_j[m];
      const Eigen::Vector3f difference = cloud_i.Point(u) - cloud_j.Point(v);
      double r[3];
      for (int c = 0; c < 3; ++c)
        r[c] = static_cast<double>(MatchNormal(kCosts[c], cloud_i, u, cloud_j, v).dot(difference));
      total.Add(r);
      const double length_mm = static_cast<double>(difference.norm()) * scale * 1e3;
      int b = 0;
      while (b < 6 && length_mm > limits_mm[b]) ++b;
      by_length[b].Add(r);
      (cloud_j.boundary[v] ? border : inside).Add(r);
      const double cosine =
          std::min(1.0, static_cast<double>(cloud_i.Normal(u).dot(cloud_j.Normal(v))));
      const double angle_deg = std::acos(cosine) * 180.0 / M_PI;
      int a = 0;
      while (a < 4 && angle_deg > angle_limits_deg[a]) ++a;
      by_angle[a].Add(r);
      const Eigen::Vector3f n_j = cloud_j.Normal(v);
      const float lateral = (difference - n_j * n_j.dot(difference)).norm();
      const double ratio = static_cast<double>(lateral / spacing(cloud_j, v));
      int q = 0;
      while (q < 5 && !(ratio <= ratio_limits[q])) ++q;
      by_ratio[q].Add(r);
      classes.back().push_back(
          static_cast<std::uint8_t>(b | (a << 3) | (cloud_j.boundary[v] << 6)));
      ratio_class.back().push_back(static_cast<std::uint8_t>(q));
    }
  }
  std::printf(
      "%zu fit matches at the model, scale %.4f m; per cost: RMS [mm], mean [mm], share "
      "of the squared sum\n",
      total.count, scale);
  std::printf("%-22s %9s %7s | %-24s | %-24s | %-24s\n", "matches", "count", "share", "paper",
              "target", "symmetric");
  Print("all", total, total, scale);
  for (int b = 0; b < 7; ++b) Print(names[b], by_length[b], total, scale);
  for (int a = 0; a < 5; ++a) Print(angle_names[a], by_angle[a], total, scale);
  for (int q = 0; q < 6; ++q) Print(ratio_names[q], by_ratio[q], total, scale);
  Print("q_j on Q_j's border", border, total, scale);
  Print("q_j inside Q_j", inside, total, scale);

  // Where the minimum moves: the first Levenberg-Marquardt step from the model (as the fast
  // solver takes it) is linear in the gradient, so each class of matches moves the parameters
  // by -H^-1 g_class, H from all matches; the sensor pose error of model + that step, RMS over
  // 500 configurations, says how much the class pulls the minimum away from the model.
  std::vector<std::size_t> free;
  for (std::size_t i = 0; i < model.mask.size(); ++i)
    if (model.mask[i]) free.push_back(i);
  auto linearize = [&](CostKind cost, const std::function<bool(int)>& select) {
    MatchProblem problem(datasets, chain, knots, free, 2, false, cost);
    problem.SetMatches(
        pairs,
        [&](std::size_t p) {
          PairMatches kept = all_matches[p];
          kept.point_i.clear();
          kept.point_j.clear();
          for (std::size_t m = 0; m < all_matches[p].size(); ++m) {
            if (!select(classes[p][m] | (ratio_class[p][m] << 8))) continue;
            kept.point_i.push_back(all_matches[p].point_i[m]);
            kept.point_j.push_back(all_matches[p].point_j[m]);
          }
          return kept;
        },
        matcher.clouds(), k_hat);
    return problem.Linearize(k_hat);
  };
  struct Class {
    std::string name;
    std::function<bool(int)> select;
  };
  std::vector<Class> selection = {{"all", [](int) { return true; }}};
  for (int b = 0; b < 7; ++b) selection.push_back({names[b], [b](int c) { return (c & 7) == b; }});
  for (int a = 0; a < 5; ++a)
    selection.push_back({angle_names[a], [a](int c) { return ((c >> 3) & 7) == a; }});
  for (int q = 0; q < 6; ++q)
    selection.push_back({ratio_names[q], [q](int c) { return (c >> 8) == q; }});
  selection.push_back({"lateral <= 1.5 spacing", [](int c) { return (c >> 8) <= 2; }});
  selection.push_back({"lateral <= 2 spacing", [](int c) { return (c >> 8) <= 3; }});
  selection.push_back({"q_j on Q_j's border", [](int c) { return ((c >> 6) & 1) != 0; }});
  selection.push_back({"q_j inside Q_j", [](int c) { return ((c >> 6) & 1) == 0; }});
  std::printf(
      "\nsensor pose error of the first LM step from the model, by the matches that pull: "
      "position RMS [mm], orientation RMS [deg]\n");
  std::printf("%-22s | %-18s | %-18s | %-18s\n", "matches", "paper", "target", "symmetric");
  std::vector<std::vector<std::string>> cells(selection.size());
  for (CostKind cost : kCosts) {
    const NormalEquations all = linearize(cost, selection[0].select);
    Eigen::MatrixXd damped = all.hessian;
    damped.diagonal() += all.hessian.diagonal().cwiseMax(1e-6) / 1e4;  // LM's first step
    const auto solver = damped.ldlt();
    for (std::size_t c = 0; c < selection.size(); ++c) {
      const NormalEquations part = c == 0 ? all : linearize(cost, selection[c].select);
      const Eigen::VectorXd step = solver.solve(-part.gradient);
      std::vector<double> moved = k_hat;
      for (std::size_t f = 0; f < free.size(); ++f) moved[free[f]] += step[static_cast<long>(f)];
      DenormalizeTranslationParameters(moved, model.JointCount(), scale);
      RobotModel stepped = model;
      FromParameterVector(moved, stepped);
      const PoseErrorStats error = SensorPoseError(model, stepped, 500, 42);
      char cell[64];
      std::snprintf(cell, sizeof cell, "%8.4f %8.5f", error.rms_position_m * 1e3,
                    error.rms_orientation_rad * 180.0 / M_PI);
      cells[c].push_back(cell);
    }
  }
  for (std::size_t c = 0; c < selection.size(); ++c)
    std::printf("%-22s | %s | %s | %s\n", selection[c].name.c_str(), cells[c][0].c_str(),
                cells[c][1].c_str(), cells[c][2].c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return Run(argc, argv); }
