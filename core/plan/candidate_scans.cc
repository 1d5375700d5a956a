#include "core/plan/candidate_scans.h"

#include <algorithm>
#include <cmath>

#include "core/calib/projection.h"
#include "core/model/kinematics.h"
#include "core/sim/ray_caster.h"
#include "core/sim/simulator.h"

namespace selfcal::plan {
namespace {

bool IsSweep(const sim::SensorModel& sensor) { return sensor.kind != SensorLayout::kDepthCamera; }

double LinePeriod(const sim::SensorModel& sensor) {
  return sensor.kind == SensorLayout::kRotatingLidar ? sensor.rotation_period : sensor.line_period;
}

// A camera's one frame: one pose, the view's.
calib::Dataset FrameDataset(const sim::SimSegment& segment, const sim::SensorModel& sensor,
                            const std::vector<double>& joints) {
  calib::Dataset dataset;
  dataset.layout = calib::PoseLayout::kOnePerScan;
  dataset.rows = static_cast<std::size_t>(sensor.height);
  dataset.cols = static_cast<std::size_t>(sensor.width);
  dataset.pose_joints = joints;
  const auto& points = segment.frames.front().points;
  for (std::size_t i = 0; i < dataset.rows * dataset.cols; ++i) {
    const Eigen::Vector3f p = i < points.size() ? points[i] : Eigen::Vector3f::Constant(NAN);
    dataset.x.push_back(p.x());
    dataset.y.push_back(p.y());
    dataset.z.push_back(p.z());
  }
  return dataset;
}

// A sweep's lines side by side in time (column c = line c, row r = its ray or point r, as the
// recording assembles them), one pose per line: the commanded joints at its measurement time, a
// LiDAR's at its middle ray's. (The engine gives a LiDAR's every ray its own pose; across one
// planning line the sensor turns by a fraction of a degree, which changes the information little
// and would cost a forward kinematics per point and pair.)
calib::Dataset SweepDataset(const sim::SimSegment& segment, const sim::SensorModel& sensor,
                            const std::vector<Eigen::Vector3d>& rays,
                            const sim::Simulator& simulator) {
  const bool lidar = sensor.kind == SensorLayout::kRotatingLidar;
  calib::Dataset dataset;
  dataset.layout = calib::PoseLayout::kOnePerColumn;
  dataset.rows = rays.size();
  dataset.cols = segment.frames.size();
  const std::size_t n = dataset.rows * dataset.cols;
  dataset.x.assign(n, NAN);
  dataset.y.assign(n, NAN);
  dataset.z.assign(n, NAN);
  const double middle_ray = lidar ? 0.5 * static_cast<double>(rays.size() - 1) : 0.0;
  for (std::size_t c = 0; c < dataset.cols; ++c) {
    const sim::SimFrame& frame = segment.frames[c];
    for (std::size_t r = 0; r < dataset.rows; ++r) {
      Eigen::Vector3d p = Eigen::Vector3d::Constant(NAN);
      if (lidar && r < frame.ranges.size()) p = static_cast<double>(frame.ranges[r]) * rays[r];
      if (!lidar && r < frame.points.size()) p = frame.points[r].cast<double>();
      dataset.x[r * dataset.cols + c] = static_cast<float>(p.x());
      dataset.y[r * dataset.cols + c] = static_cast<float>(p.y());
      dataset.z[r * dataset.cols + c] = static_cast<float>(p.z());
    }
    const std::vector<double> q = simulator.CommandedJoints(
        static_cast<double>(frame.device_stamp_us) * 1e-6 + middle_ray * sensor.time_per_ray);
    dataset.pose_joints.insert(dataset.pose_joints.end(), q.begin(), q.end());
  }
  return dataset;
}

// The views' index whose scan time is the median.
int MedianView(const sim::Simulator& simulator) {
  std::vector<std::pair<double, int>> seconds;
  for (int k = 0; k < simulator.SegmentCount(); ++k)
    seconds.emplace_back(simulator.ScanSeconds(k), k);
  std::nth_element(seconds.begin(), seconds.begin() + static_cast<long>(seconds.size() / 2),
                   seconds.end());
  return seconds[seconds.size() / 2].second;
}

// Median distance [m] in the base frame between neighbours of `dataset`'s grid: along a line
// (rows r, r + 1) and from line to line (columns c, c + 1).
std::pair<double, double> GridSpacing(const calib::Dataset& dataset, const RobotModel& nominal) {
  const std::vector<double> k = ToParameterVector(nominal);
  const calib::ProjectedCloud cloud =
      calib::ProjectDataset(dataset, calib::Chain{JointTypes(nominal), 1.0, false}, k.data());
  std::vector<double> along, across;
  auto distance = [&](std::size_t a, std::size_t b, std::vector<double>& out) {
    if (cloud.Valid(a) && cloud.Valid(b)) out.push_back((cloud.Point(a) - cloud.Point(b)).norm());
  };
  for (std::size_t r = 0; r < dataset.rows; ++r) {
    for (std::size_t c = 0; c < dataset.cols; ++c) {
      const std::size_t i = r * dataset.cols + c;
      if (r + 1 < dataset.rows) distance(i, i + dataset.cols, along);
      if (c + 1 < dataset.cols) distance(i, i + 1, across);
    }
  }
  auto median = [](std::vector<double>& values) {
    if (values.empty()) return 0.0;
    std::nth_element(values.begin(), values.begin() + static_cast<long>(values.size() / 2),
                     values.end());
    return values[values.size() / 2];
  };
  return {median(along), median(across)};
}

// The sensor seeing every `thinning.along`-th point of a line and every `thinning.lines`-th
// line: a camera binned (both equal), a LiDAR with every along-th ray at its own time, a line
// scanner with an along times sparser fan.
sim::SensorModel Thinned(const sim::SensorModel& sensor, const Thinning& thinning) {
  if (!IsSweep(sensor)) return sensor.Binned(thinning.along);
  sim::SensorModel thinned = sensor;
  thinned.width = std::max(1, sensor.width / thinning.along);
  if (sensor.kind == SensorLayout::kRotatingLidar) {
    thinned.angle_increment *= thinning.along;
    thinned.time_per_ray *= thinning.along;
    thinned.rotation_period *= thinning.lines;
  } else {
    thinned.line_period *= thinning.lines;
  }
  return thinned;
}

}  // namespace

Thinning PlanningThinning(const sim::SensorModel& sensor, double lines, double spacing_ratio,
                          int cells) {
  for (int step = 1;; ++step) {
    Thinning thinning{step, step};
    if (IsSweep(sensor) && spacing_ratio > 0) {
      // Points as far apart along a line as the lines are from each other.
      const double ratio = std::clamp(spacing_ratio, 1e-3, 1e3);
      thinning.along = std::max(1, static_cast<int>(std::lround(step * std::min(1.0, ratio))));
      thinning.lines = std::max(1, static_cast<int>(std::lround(step / std::max(1.0, ratio))));
    }
    const double kept = IsSweep(sensor) ? static_cast<double>(sensor.width / thinning.along) *
                                              std::max(1.0, lines) / thinning.lines
                                        : static_cast<double>(sensor.CellCount() / (step * step));
    if (kept <= cells || step >= 256) return thinning;
  }
}

Expected<SimulatedViews> SimulateViews(const RobotModel& nominal, const sim::SensorModel& sensor,
                                       const sim::Scene& scene,
                                       const std::vector<sim::PlannedScan>& views, int cells,
                                       double min_coverage, const PlanProgress& progress) {
  auto caster = sim::RayCaster::Create(scene);
  if (!caster) return Error{"scene " + scene.name + ": " + caster.error().message};
  sim::RecordingOptions recording;
  recording.encoder_noise = 0;
  recording.timestamp_jitter = 0;
  sim::ScanPlan plan;
  plan.scans = views;
  sim::SensorModel ideal = sensor;
  ideal.sigma_abs = ideal.sigma_rel = 0;
  SimulatedViews out;
  double lines = 1, spacing_ratio = 0;
  if (IsSweep(sensor) && !views.empty()) {
    // One sweep at the sensor's own resolution tells how far apart its lines fall.
    const sim::Simulator full(nominal, ideal, **caster, plan, recording);
    const int median = MedianView(full);
    lines = full.ScanSeconds(median) / LinePeriod(sensor);
    const sim::SimSegment segment = full.Segment(median);
    if (!segment.frames.empty()) {
      const auto [along, across] =
          GridSpacing(SweepDataset(segment, ideal, ideal.Rays(), full), nominal);
      if (along > 0 && across > 0) spacing_ratio = across / along;
    }
  }
  out.thinning = PlanningThinning(sensor, lines, spacing_ratio, cells);
  const sim::SensorModel planning = Thinned(ideal, out.thinning);
  const std::vector<Eigen::Vector3d> rays = planning.Rays();
  const sim::Simulator simulator(nominal, planning, **caster, plan, recording);
  double full_count = 0, kept_count = 0;
  for (std::size_t v = 0; v < views.size(); ++v) {
    const sim::SimSegment segment = simulator.Segment(static_cast<int>(v));
    if (segment.frames.empty()) continue;
    calib::Dataset dataset = IsSweep(planning) ? SweepDataset(segment, planning, rays, simulator)
                                               : FrameDataset(segment, planning, views[v].start);
    dataset.scan_index = static_cast<int>(v);
    dataset.joint_count = nominal.JointCount();
    if (static_cast<double>(dataset.ValidPointCount()) <
        min_coverage * static_cast<double>(dataset.PointCount()))
      continue;
    full_count += IsSweep(planning) ? sensor.width * simulator.ScanSeconds(static_cast<int>(v)) /
                                          LinePeriod(sensor)
                                    : sensor.CellCount();
    kept_count += static_cast<double>(dataset.PointCount());
    out.datasets.push_back(std::move(dataset));
    out.sighted.push_back(static_cast<int>(v));
    if (progress && ((v + 1) % 20 == 0 || v + 1 == views.size()))
      progress("simulated " + std::to_string(v + 1) + "/" + std::to_string(views.size()) +
               " candidate views (" + std::to_string(out.sighted.size()) + " see the scene)");
  }
  out.measurements_per_kept = kept_count > 0 ? full_count / kept_count : 1.0;
  return out;
}

}  // namespace selfcal::plan
