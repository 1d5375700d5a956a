#include "core/sim/simulator.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/model/kinematics.h"
#include "core/sim/device_frame.h"
#include "core/sim/random.h"

namespace selfcal::sim {
namespace {

constexpr std::uint64_t kEncoderLabel = 0xe4c0de;
constexpr std::uint64_t kJitterLabel = 0x717e4;
constexpr std::uint64_t kSensorLabel = 0x5e4503;
constexpr std::uint64_t kMixedPixelLabel = 0x313ed;
constexpr std::uint64_t kDarkDropoutLabel = 0xda4c;
constexpr std::uint64_t kSpeckleLabel = 0x5bec1e;

std::int64_t ToMicros(double seconds) {
  return static_cast<std::int64_t>(std::llround(seconds * 1e6));
}
std::int64_t CeilMicros(double seconds) {
  return static_cast<std::int64_t>(std::ceil(seconds * 1e6 - 1e-6));
}
double Seconds(std::int64_t micros) { return static_cast<double>(micros) * 1e-6; }

// Path acceleration [1/s^2] of a scan move within `fraction` of the joint limits.
double PathAcceleration(const RobotModel& model, const PlannedScan& scan, double fraction) {
  double acceleration = 1e9;
  for (std::size_t j = 0; j < scan.start.size(); ++j) {
    const double distance = std::abs(scan.end[j] - scan.start[j]);
    if (distance > 1e-12) {
      acceleration = std::min(acceleration, fraction * model.joints[j].max_acceleration / distance);
    }
  }
  return acceleration;
}

}  // namespace

Simulator::Simulator(RobotModel truth, SensorModel sensor, const RayCaster& caster, ScanPlan plan,
                     RecordingOptions options)
    : truth_(std::move(truth)),
      joint_types_(JointTypes(truth_)),
      truth_parameters_(ToParameterVector(truth_)),
      sensor_(std::move(sensor)),
      rays_(sensor_.Rays()),
      true_rays_(TrueSensorModel(sensor_, options.effects.intrinsics).Rays()),
      caster_(caster),
      plan_(std::move(plan)),
      options_(options) {
  // Lay out the whole recording: an initial hold, then per scan a transit, settling, the scan
  // and settling again. Scan boundaries sit on whole microseconds.
  double t = 0;
  for (std::size_t k = 0; k < plan_.scans.size(); ++k) {
    const PlannedScan& scan = plan_.scans[k];
    ScanTiming timing{};
    timing.segment_start_us = ToMicros(t);
    if (k == 0) {
      timeline_.Append(JointMove::Hold(scan.start, t, 0.5));
    } else {
      timeline_.Append(JointMove::Transit(truth_, timeline_.FinalPositions(), scan.start, t,
                                          options_.transit_fraction));
    }
    t = timeline_.end_time();
    const double begin = Seconds(CeilMicros(t + options_.settle_time));
    timeline_.Append(JointMove::Hold(scan.start, t, begin - t));
    timing.begin_us = ToMicros(begin);
    if (scan.peak_rate > 0) {
      // Scan moves use the full acceleration limits: the constant-velocity phase the paper asks
      // for should dominate the sweep.
      timeline_.Append(JointMove::Line(scan.start, scan.end, begin, scan.peak_rate,
                                       PathAcceleration(truth_, scan, 1.0)));
    } else {
      timeline_.Append(JointMove::Hold(scan.end, begin, options_.stationary_hold));
    }
    t = timeline_.end_time();
    const double end = Seconds(CeilMicros(t));
    timing.end_us = ToMicros(end);
    const double segment_end = Seconds(CeilMicros(end + options_.settle_time));
    timeline_.Append(JointMove::Hold(scan.end, t, segment_end - t));
    t = timeline_.end_time();
    timing.segment_end_us = ToMicros(segment_end);
    timings_.push_back(timing);
  }
  // Every move is monotonic in each joint, so the output at a move's start and the input at t
  // give the output at t (the play operator).
  if (options_.effects.backlash.enabled && !timeline_.empty()) {
    std::vector<double> output = timeline_.moves().front().from();
    for (const JointMove& move : timeline_.moves()) {
      backlash_starts_.push_back(output);
      for (std::size_t j = 0; j < output.size(); ++j) {
        output[j] = PlayOutput(output[j], move.to()[j], options_.effects.backlash.angle);
      }
    }
  }
}

const double* Simulator::TrueParameters(double t, std::vector<double>& storage) const {
  if (!options_.effects.thermal_growth.enabled) return truth_parameters_.data();
  storage = truth_parameters_;
  GrowLinks(options_.effects.thermal_growth, t, truth_.JointCount(), storage.data());
  return storage.data();
}

void Simulator::TrueConfiguration(double t, const double* parameters, double* q) const {
  timeline_.Evaluate(t, q, nullptr);
  if (options_.effects.backlash.enabled) {
    const std::vector<double>& start = backlash_starts_[timeline_.MoveIndex(t)];
    for (std::size_t j = 0; j < start.size(); ++j) {
      q[j] = PlayOutput(start[j], q[j], options_.effects.backlash.angle);
    }
  }
  DeflectJoints(options_.effects.joint_elasticity, joint_types_, parameters, q);
}

Eigen::Isometry3d Simulator::PoseOf(const double* q, const double* parameters) const {
  return ForwardKinematics<double, double>(joint_types_, parameters, q);
}

Eigen::Isometry3d Simulator::TrueSensorPose(double t) const {
  std::vector<double> q(truth_.JointCount()), grown;
  const double* parameters = TrueParameters(t, grown);
  TrueConfiguration(t, parameters, q.data());
  return PoseOf(q.data(), parameters);
}

std::vector<double> Simulator::CommandedJoints(double t) const {
  std::vector<double> q(truth_.JointCount());
  timeline_.Evaluate(t, q.data(), nullptr);
  return q;
}

double Simulator::ScanBegin(int k) const {
  return static_cast<double>(timings_[static_cast<std::size_t>(k)].begin_us) * 1e-6;
}

double Simulator::ScanSeconds(int k) const {
  const ScanTiming& timing = timings_[static_cast<std::size_t>(k)];
  return static_cast<double>(timing.end_us - timing.begin_us) * 1e-6;
}

SimSegment Simulator::Segment(int k) const {
  const ScanTiming& timing = timings_[static_cast<std::size_t>(k)];
  const PlannedScan& scan = plan_.scans[static_cast<std::size_t>(k)];
  SimSegment segment;
  segment.scan_index = k;
  segment.start_us = timing.segment_start_us;
  segment.end_us = timing.segment_end_us;

  // Joint states on the controller's fixed clock; samples belong to the segment their ideal
  // time falls in, so segments neither overlap nor leave gaps.
  const double rate = options_.joint_rate_hz;
  const auto first =
      static_cast<std::int64_t>(std::ceil(Seconds(timing.segment_start_us) * rate - 1e-9));
  const CounterRandom encoder(SubKey(options_.seed, kEncoderLabel));
  const CounterRandom jitter(SubKey(options_.seed, kJitterLabel));
  const std::size_t n = truth_.JointCount();
  const double max_jitter = 0.4 / rate;  // keeps host stamps in order
  for (std::int64_t sample = first;; ++sample) {
    const double t = static_cast<double>(sample) / rate;
    if (ToMicros(t) >= timing.segment_end_us && k + 1 < SegmentCount()) break;
    if (ToMicros(t) > timing.segment_end_us) break;
    SimJointState state;
    state.positions.resize(n);
    state.velocities.resize(n);
    // Joint states that lag the motion report where the arm was `joint_lag` ago.
    const TimingEffect& timing_effect = options_.effects.timing;
    timeline_.Evaluate(timing_effect.enabled ? t - timing_effect.joint_lag : t,
                       state.positions.data(), state.velocities.data());
    for (std::size_t j = 0; j < n; ++j) {
      state.positions[j] +=
          options_.encoder_noise * encoder.Gaussian(static_cast<std::uint64_t>(sample) * n + j);
    }
    const double dt =
        std::clamp(options_.timestamp_jitter * jitter.Gaussian(static_cast<std::uint64_t>(sample)),
                   -max_jitter, max_jitter);
    state.stamp_us = ToMicros(t + dt);
    state.device_stamp_us = ToMicros(t);
    segment.joint_states.push_back(std::move(state));
  }

  segment.markers.push_back({timing.begin_us, true, scan.purpose, k});
  segment.markers.push_back({timing.end_us, false, scan.purpose, k});
  SimulateFrames(k, timing, segment.frames);
  return segment;
}

std::vector<std::int64_t> Simulator::FrameStamps(const ScanTiming& timing,
                                                 std::int64_t& period_us) const {
  std::int64_t last_offset_us = 0;  // from the stamp to the last measurement of a frame
  std::int64_t first_offset_us = 0;
  switch (sensor_.kind) {
    case SensorLayout::kRotatingLidar:
      period_us = ToMicros(sensor_.rotation_period);
      last_offset_us = CeilMicros((sensor_.width - 1) * sensor_.time_per_ray);
      break;
    case SensorLayout::kLineScanner:
      period_us = ToMicros(sensor_.line_period);
      break;
    case SensorLayout::kDepthCamera:
      // One frame in the middle of the stationary hold.
      period_us = std::numeric_limits<std::int64_t>::max() / 4;
      first_offset_us = (timing.end_us - timing.begin_us) / 2;
      break;
  }
  std::vector<std::int64_t> stamps;
  for (std::int64_t stamp = timing.begin_us + first_offset_us;
       stamp + last_offset_us <= timing.end_us; stamp += period_us) {
    stamps.push_back(stamp);
  }
  return stamps;
}

void Simulator::SimulateFrames(int k, const ScanTiming& timing,
                               std::vector<SimFrame>& frames) const {
  const std::int64_t latency_us = ToMicros(options_.latency);
  std::int64_t period_us = 0;
  const std::vector<std::int64_t> stamps = FrameStamps(timing, period_us);
  frames.resize(stamps.size());
  const CounterRandom noise(SubKey(options_.seed, kSensorLabel, static_cast<std::uint64_t>(k)));
  const std::size_t cells = static_cast<std::size_t>(sensor_.CellCount());
  const float nan = std::numeric_limits<float>::quiet_NaN();

  auto simulate_frame = [&](std::size_t f) {
    SimFrame& frame = frames[f];
    frame.stamp_us = stamps[f];
    // Counters continue across scans as a device's would (one per period since the start).
    frame.counter = sensor_.kind == SensorLayout::kDepthCamera ? k : stamps[f] / period_us;
    double measured = Seconds(stamps[f] + latency_us);
    frame.device_stamp_us = stamps[f] + latency_us;
    // A sensor clock running fast stamps its messages ahead of the true measurement time.
    if (options_.effects.timing.enabled) {
      measured -= options_.effects.timing.clock_drift_ppm * 1e-6 * Seconds(stamps[f]);
    }
    std::vector<double> q(truth_.JointCount()), grown;
    // Thermal growth is slow: one set of parameters per frame.
    const double* parameters = TrueParameters(measured, grown);
    auto pose_at = [&](double t) {
      TrueConfiguration(t, parameters, q.data());
      return PoseOf(q.data(), parameters);
    };
    const std::uint64_t base = static_cast<std::uint64_t>(f) * cells;
    if (options_.effects.AnyMeasurementEffect()) {
      SimulateFieldFrame(k, timing, measured, base, frame);
      return;
    }
    if (sensor_.kind == SensorLayout::kRotatingLidar) {
      frame.ranges.assign(cells, nan);
      for (std::size_t i = 0; i < cells; ++i) {
        const Eigen::Isometry3d T =
            pose_at(measured + static_cast<double>(i) * sensor_.time_per_ray);
        const double range =
            caster_.Cast(T.translation(), T.linear() * rays_[i], sensor_.range_max * 1.1);
        if (!std::isfinite(range)) continue;
        const double noisy = range + sensor_.Sigma(range) * noise.Gaussian(base + i);
        if (noisy >= sensor_.range_min && noisy <= sensor_.range_max)
          frame.ranges[i] = static_cast<float>(noisy);
      }
      return;
    }
    frame.points.assign(cells, Eigen::Vector3f::Constant(nan));
    const Eigen::Isometry3d T = pose_at(measured);
    const std::size_t width = static_cast<std::size_t>(sensor_.width);
    // Rows in parallel (a camera scan has a single frame); each cell writes only its own slot.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, static_cast<std::size_t>(sensor_.height)),
                      [&](const tbb::blocked_range<std::size_t>& rows) {
                        for (std::size_t i = rows.begin() * width; i < rows.end() * width; ++i) {
                          const Eigen::Vector3d& ray = rays_[i];  // scaled to z = 1
                          const double length = ray.norm();
                          const double distance =
                              caster_.Cast(T.translation(), T.linear() * (ray / length),
                                           sensor_.range_max * length * 1.1);
                          if (!std::isfinite(distance)) continue;
                          const double z = distance / length;
                          const double noisy = z + sensor_.Sigma(z) * noise.Gaussian(base + i);
                          if (noisy >= sensor_.range_min && noisy <= sensor_.range_max) {
                            frame.points[i] = (ray * noisy).cast<float>();
                          }
                        }
                      });
  };
  // Frames are independent and each writes only its own slot: thread count cannot change bytes.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, frames.size()),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t f = range.begin(); f != range.end(); ++f) simulate_frame(f);
                    });
}

bool Simulator::Shadowed(const Eigen::Isometry3d& T_base_sensor, const Eigen::Vector3d& point,
                         const DynamicGeometry& geometry) const {
  return ShadowedFromSecondViewpoint(caster_, geometry, options_.effects.baseline_shadows,
                                     sensor_.kind, T_base_sensor, point);
}

void Simulator::MeasureFieldCells(int k, double measured, std::uint64_t base,
                                  const DynamicGeometry& geometry, std::vector<double>& measures,
                                  std::vector<double>& cosines) const {
  const FieldEffects& effects = options_.effects;
  const bool lidar = sensor_.kind == SensorLayout::kRotatingLidar;
  const std::size_t cells = static_cast<std::size_t>(sensor_.CellCount());
  std::vector<double> q(truth_.JointCount()), grown;
  const double* parameters = TrueParameters(measured, grown);
  TrueConfiguration(measured, parameters, q.data());
  const Eigen::Isometry3d frame_pose = PoseOf(q.data(), parameters);
  const CounterRandom dropout(
      SubKey(options_.seed, kDarkDropoutLabel, static_cast<std::uint64_t>(k)));
  // Per cell: the distance along the ray, the albedo, and (for multipath) point and normal.
  std::vector<double> distances(cells, 0.0), albedos(cells, 1.0);
  std::vector<char> valid(cells, 0);
  std::vector<Eigen::Vector3d> points, normals;
  if (effects.multipath.enabled) {
    points.resize(cells);
    normals.resize(cells);
  }
  auto cast_cell = [&](std::size_t i, const Eigen::Isometry3d& T) {
    const Eigen::Vector3d& ray = true_rays_[i];
    const double length = ray.norm();
    const Eigen::Vector3d direction = T.linear() * (ray / length);
    const RayReturn hit = CastFieldRay(caster_, geometry, effects, T.translation(), direction,
                                       sensor_.range_max * length * 1.1);
    if (!std::isfinite(hit.distance)) return;
    const Eigen::Vector3d point = T.translation() + hit.distance * direction;
    if (effects.baseline_shadows.enabled && !lidar && Shadowed(T, point, geometry)) return;
    if (LostOnDarkSurface(effects.dark_dropout, hit.albedo, hit.cosine, hit.distance,
                          dropout.Uniform(base + i))) {
      return;
    }
    valid[i] = 1;
    distances[i] = hit.distance;
    albedos[i] = hit.albedo;
    cosines[i] = hit.cosine;
    if (effects.multipath.enabled) {
      points[i] = point;
      normals[i] = hit.normal;
    }
  };
  if (lidar) {
    for (std::size_t i = 0; i < cells; ++i) {
      TrueConfiguration(measured + static_cast<double>(i) * sensor_.time_per_ray, parameters,
                        q.data());
      cast_cell(i, PoseOf(q.data(), parameters));
    }
  } else {
    const std::size_t width = static_cast<std::size_t>(sensor_.width);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, static_cast<std::size_t>(sensor_.height)),
                      [&](const tbb::blocked_range<std::size_t>& rows) {
                        for (std::size_t i = rows.begin() * width; i < rows.end() * width; ++i) {
                          cast_cell(i, frame_pose);
                        }
                      });
  }
  // Multipath lengthens the path along the ray; the depth grows by the same fraction.
  const std::vector<double> excess =
      MultipathGrid(effects.multipath, caster_, geometry, sensor_.width, sensor_.height, points,
                    normals, valid, kMultipathGridStep);
  for (std::size_t i = 0; i < cells; ++i) {
    if (!valid[i]) continue;
    const double length = true_rays_[i].norm();
    measures[i] = SystematicMeasure(effects, (distances[i] + excess[i]) / length, cosines[i],
                                    measured, albedos[i]);
  }
}

std::vector<double> Simulator::CellNoise(int k, std::uint64_t base) const {
  const std::size_t cells = static_cast<std::size_t>(sensor_.CellCount());
  const std::uint64_t frame = base / cells;  // base = frame * cells
  const CounterRandom noise(SubKey(options_.seed, kSensorLabel, static_cast<std::uint64_t>(k)));
  if (options_.effects.speckle.enabled && sensor_.kind == SensorLayout::kLineScanner) {
    const CounterRandom white(SubKey(options_.seed, kSpeckleLabel, static_cast<std::uint64_t>(k)));
    const std::uint64_t stride =
        cells + static_cast<std::uint64_t>(SpeckleSupport(options_.effects.speckle));
    return SpeckleNoise(options_.effects.speckle, static_cast<int>(cells),
                        [&](std::size_t j) { return white.Gaussian(frame * stride + j); });
  }
  std::vector<double> unit(cells);
  for (std::size_t i = 0; i < cells; ++i) unit[i] = noise.Gaussian(base + i);
  return unit;
}

void Simulator::SimulateFieldFrame(int k, const ScanTiming& timing, double measured,
                                   std::uint64_t base, SimFrame& frame) const {
  const FieldEffects& effects = options_.effects;
  const bool lidar = sensor_.kind == SensorLayout::kRotatingLidar;
  const std::size_t cells = static_cast<std::size_t>(sensor_.CellCount());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> q(truth_.JointCount()), grown;

  // What moves, once per frame (the arm turns about a quarter degree in a LiDAR rotation).
  const double middle =
      lidar ? measured + 0.5 * (sensor_.width - 1) * sensor_.time_per_ray : measured;
  DynamicGeometry geometry;
  if (effects.self_view.enabled) {
    const double* parameters = TrueParameters(middle, grown);
    TrueConfiguration(middle, parameters, q.data());
    geometry.capsules =
        ArmCapsules(ComputeArmFrames(joint_types_, parameters, q.data()), effects.self_view.radius);
  }
  const double scan_time = Seconds(timing.end_us - timing.begin_us);
  AddSceneMotion(effects, k, scan_time > 0 ? (middle - Seconds(timing.begin_us)) / scan_time : 0,
                 geometry);

  // Pass 1: the clean measure (range or depth) with the systematic errors, per cell.
  std::vector<double> measures(cells, nan), cosines(cells, 1.0);
  MeasureFieldCells(k, measured, base, geometry, measures, cosines);

  // Pass 2: flying pixels where neighbours jump, then the noise along the ray.
  const CounterRandom mix(SubKey(options_.seed, kMixedPixelLabel, static_cast<std::uint64_t>(k)));
  const std::vector<double> mixed = MixPixels(
      effects.mixed_pixels, measures, sensor_.width, sensor_.height, [&](std::size_t i, int draw) {
        return mix.Uniform(2 * (base + i) + static_cast<std::uint64_t>(draw));
      });
  const std::vector<double> unit = CellNoise(k, base);
  const float nan_f = std::numeric_limits<float>::quiet_NaN();
  if (lidar) {
    frame.ranges.assign(cells, nan_f);
  } else {
    frame.points.assign(cells, Eigen::Vector3f::Constant(nan_f));
  }
  for (std::size_t i = 0; i < cells; ++i) {
    const double m = mixed[i];
    if (!std::isfinite(m)) continue;
    const double sigma =
        sensor_.Sigma(m) * IncidenceNoiseFactor(effects.incidence_noise, cosines[i]);
    const double noisy = m + sigma * unit[i];
    if (!(noisy >= sensor_.range_min && noisy <= sensor_.range_max)) continue;
    if (lidar) {
      frame.ranges[i] = static_cast<float>(noisy);
    } else {
      frame.points[i] = (rays_[i] * noisy).cast<float>();
    }
  }
}

}  // namespace selfcal::sim
