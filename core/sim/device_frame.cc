#include "core/sim/device_frame.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>

#include "core/model/kinematics.h"
#include "core/sim/random.h"

namespace selfcal::sim {
namespace {

// Labels of the device frames' random streams, consecutive (selfcal-sim-scip's since it served
// them first).
enum StreamLabel : std::uint64_t { kNoiseLabel = 0x5c1b0, kMixLabel, kDropoutLabel, kSpeckleLabel };

CellReturns NoReturns(std::size_t cells) {
  CellReturns out;
  out.measures.assign(cells, std::numeric_limits<double>::quiet_NaN());
  out.cosines.assign(cells, 1.0);
  out.distances.assign(cells, 0.0);
  out.albedos.assign(cells, 1.0);
  return out;
}

}  // namespace

SensorModel TrueSensorModel(SensorModel sensor, const IntrinsicsEffect& effect) {
  if (!effect.enabled) return sensor;
  const double scale = 1 + effect.focal_scale;
  sensor.intrinsics.fx *= scale;
  sensor.intrinsics.fy *= scale;
  sensor.fan_angle /= scale;
  sensor.angle_first /= scale;
  sensor.angle_increment /= scale;
  return sensor;
}

DeviceFrameCaster::DeviceFrameCaster(const RayCaster& caster, const RobotModel& truth,
                                     SensorModel sensor, FieldEffects effects, std::uint64_t seed)
    : caster_(caster),
      joint_types_(JointTypes(truth)),
      parameters_(ToParameterVector(truth)),
      sensor_(std::move(sensor)),
      effects_(std::move(effects)),
      seed_(seed),
      rays_(sensor_.Rays()),
      true_rays_(TrueSensorModel(sensor_, effects_.intrinsics).Rays()) {}

double DeviceFrameCaster::FocalFactor() const {
  return effects_.intrinsics.enabled ? 1 + effects_.intrinsics.focal_scale : 1.0;
}

Eigen::Isometry3d DeviceFrameCaster::SensorPose(std::span<const double> q, double elapsed) const {
  std::vector<double> parameters = parameters_;
  GrowLinks(effects_.thermal_growth, elapsed, joint_types_.size(), parameters.data());
  std::vector<double> deflected(q.begin(), q.end());
  DeflectJoints(effects_.joint_elasticity, joint_types_, parameters.data(), deflected.data());
  return ForwardKinematics<double, double>(joint_types_, parameters.data(), deflected.data());
}

DynamicGeometry DeviceFrameCaster::ArmLinks(std::span<const double> q) const {
  DynamicGeometry geometry;
  if (!effects_.self_view.enabled) return geometry;
  std::vector<double> deflected(q.begin(), q.end());
  DeflectJoints(effects_.joint_elasticity, joint_types_, parameters_.data(), deflected.data());
  geometry.capsules =
      ArmCapsules(ComputeArmFrames(joint_types_, parameters_.data(), deflected.data()),
                  effects_.self_view.radius);
  return geometry;
}

DynamicGeometry DeviceFrameCaster::Moving(std::span<const double> q, int scan,
                                          double fraction) const {
  DynamicGeometry geometry = ArmLinks(q);
  AddSceneMotion(effects_, scan, fraction, geometry);
  return geometry;
}

DeviceFrameCaster::Hits DeviceFrameCaster::NoHits(std::size_t cells) const {
  Hits hits;
  if (!effects_.multipath.enabled) return hits;
  hits.points.resize(cells);
  hits.normals.resize(cells);
  hits.valid.assign(cells, 0);
  return hits;
}

void DeviceFrameCaster::CastCell(std::size_t i, const Eigen::Vector3d& ray,
                                 const Eigen::Isometry3d& T, const DynamicGeometry& geometry,
                                 CellReturns& out, Hits& hits) const {
  const double length = ray.norm();
  const Eigen::Vector3d direction = T.linear() * (ray / length);
  const RayReturn hit = CastFieldRay(caster_, geometry, effects_, T.translation(), direction,
                                     sensor_.range_max * length * 1.1);
  if (!std::isfinite(hit.distance)) return;
  if (effects_.baseline_shadows.enabled && sensor_.kind != SensorLayout::kRotatingLidar &&
      ShadowedFromSecondViewpoint(caster_, geometry, effects_.baseline_shadows, sensor_.kind, T,
                                  T.translation() + hit.distance * direction)) {
    return;
  }
  out.measures[i] = hit.distance / length;
  out.cosines[i] = hit.cosine;
  out.distances[i] = hit.distance;
  out.albedos[i] = hit.albedo;
  if (hits.valid.empty()) return;
  hits.points[i] = T.translation() + hit.distance * direction;
  hits.normals[i] = hit.normal;
  hits.valid[i] = 1;
}

void DeviceFrameCaster::AddMultipath(std::span<const Eigen::Vector3d> rays, int width,
                                     const DynamicGeometry& geometry, const Hits& hits,
                                     CellReturns& out) const {
  if (hits.valid.empty()) return;
  const int height = static_cast<int>(rays.size()) / width;
  const std::vector<double> excess =
      MultipathGrid(effects_.multipath, caster_, geometry, width, height, hits.points, hits.normals,
                    hits.valid, kMultipathGridStep);
  // The path grows along the ray; the distance (of the dark-surface dropout) stays the hit's.
  for (std::size_t i = 0; i < rays.size(); ++i) {
    if (hits.valid[i]) out.measures[i] = (out.distances[i] + excess[i]) / rays[i].norm();
  }
}

CellReturns DeviceFrameCaster::Cast(std::span<const Eigen::Vector3d> rays, int width,
                                    const Eigen::Isometry3d& T_base_sensor,
                                    const DynamicGeometry& geometry) const {
  CellReturns out = NoReturns(rays.size());
  Hits hits = NoHits(rays.size());
  // Each cell writes only its own slot: the thread count cannot change the frame.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), 4096),
                    [&](const tbb::blocked_range<std::size_t>& cells) {
                      for (std::size_t i = cells.begin(); i != cells.end(); ++i) {
                        CastCell(i, rays[i], T_base_sensor, geometry, out, hits);
                      }
                    });
  AddMultipath(rays, width, geometry, hits, out);
  return out;
}

CellReturns DeviceFrameCaster::Cast(
    std::span<const Eigen::Vector3d> rays,
    const std::function<Eigen::Isometry3d(std::size_t)>& T_base_sensor_of_cell,
    const DynamicGeometry& geometry) const {
  CellReturns out = NoReturns(rays.size());
  Hits hits = NoHits(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    CastCell(i, rays[i], T_base_sensor_of_cell(i), geometry, out, hits);
  }
  AddMultipath(rays, static_cast<int>(rays.size()), geometry, hits, out);
  return out;
}

std::vector<double> DeviceFrameCaster::UnitNoise(std::size_t cells, std::uint64_t frame_key) const {
  if (effects_.speckle.enabled && sensor_.kind == SensorLayout::kLineScanner) {
    const CounterRandom white(SubKey(seed_, kSpeckleLabel, frame_key));
    return SpeckleNoise(effects_.speckle, static_cast<int>(cells),
                        [&](std::size_t j) { return white.Gaussian(j); });
  }
  const CounterRandom noise(SubKey(seed_, kNoiseLabel, frame_key));
  std::vector<double> unit(cells);
  for (std::size_t i = 0; i < cells; ++i) unit[i] = noise.Gaussian(i);
  return unit;
}

std::vector<double> DeviceFrameCaster::Measure(const CellReturns& cells, int width, int height,
                                               double device_time, std::uint64_t frame_key) const {
  std::vector<double> measures(cells.measures.size());
  const CounterRandom dropout(SubKey(seed_, kDropoutLabel, frame_key));
  for (std::size_t i = 0; i < measures.size(); ++i) {
    const double m = cells.measures[i];
    const bool lost = !std::isfinite(m) ||
                      LostOnDarkSurface(effects_.dark_dropout, cells.albedos[i], cells.cosines[i],
                                        cells.distances[i], dropout.Uniform(i));
    measures[i] =
        lost ? std::numeric_limits<double>::quiet_NaN()
             : SystematicMeasure(effects_, m, cells.cosines[i], device_time, cells.albedos[i]);
  }
  const CounterRandom mix(SubKey(seed_, kMixLabel, frame_key));
  measures =
      MixPixels(effects_.mixed_pixels, measures, width, height, [&](std::size_t i, int draw) {
        return mix.Uniform(2 * i + static_cast<std::uint64_t>(draw));
      });
  const std::vector<double> unit = UnitNoise(measures.size(), frame_key);
  for (std::size_t i = 0; i < measures.size(); ++i) {
    double& m = measures[i];
    if (!std::isfinite(m)) continue;
    const double sigma =
        sensor_.Sigma(m) * IncidenceNoiseFactor(effects_.incidence_noise, cells.cosines[i]);
    m += sigma * unit[i];
    if (!(m >= sensor_.range_min && m <= sensor_.range_max)) {
      m = std::numeric_limits<double>::quiet_NaN();
    }
  }
  return measures;
}

}  // namespace selfcal::sim
