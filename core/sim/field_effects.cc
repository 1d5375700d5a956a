#include "core/sim/field_effects.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/model/kinematics.h"

namespace selfcal::sim {

bool FieldEffects::AnyMeasurementEffect() const {
  return mixed_pixels.enabled || range_bias.enabled || incidence_noise.enabled ||
         grazing_dropout.enabled || baseline_shadows.enabled || intrinsics.enabled ||
         self_view.enabled || walker.enabled || moved_object.enabled || multipath.enabled ||
         dark_dropout.enabled || speckle.enabled;
}

bool FieldEffects::AnyEnabled() const {
  return AnyMeasurementEffect() || joint_elasticity.enabled || timing.enabled ||
         thermal_growth.enabled || backlash.enabled;
}

double RangeBias(const RangeBiasEffect& effect, double measure, double cos_incidence, double t,
                 double albedo) {
  if (!effect.enabled) return 0;
  double bias = effect.offset + effect.per_metre * measure +
                effect.incidence * (1 - std::clamp(cos_incidence, 0.0, 1.0));
  if (effect.warmup_offset != 0) {
    bias += effect.warmup_offset * std::exp(-t / effect.warmup_time_constant);
  }
  if (effect.reflectivity != 0) bias += effect.reflectivity * (1 - std::clamp(albedo, 0.0, 1.0));
  return bias;
}

double ReturnedSignal(double albedo, double cosine, double range) {
  return albedo * std::abs(cosine) / (range * range);
}

bool LostOnDarkSurface(const DarkDropoutEffect& effect, double albedo, double cosine, double range,
                       double uniform) {
  if (!effect.enabled) return false;
  const double s = ReturnedSignal(albedo, cosine, range);
  return s < effect.threshold && uniform < 1 - s / effect.threshold;
}

int SpeckleSupport(const SpeckleEffect& effect) {
  return 2 * static_cast<int>(std::ceil(1.5 * effect.correlation_length));
}

double ThermalScale(const ThermalGrowthEffect& effect, double t) {
  if (!effect.enabled) return 1;
  const double rise =
      effect.temperature_rise * (1 - std::exp(-std::max(t, 0.0) / effect.time_constant));
  return 1 + effect.expansion * rise;
}

void GrowLinks(const ThermalGrowthEffect& effect, double t, std::size_t joint_count,
               double* parameters) {
  if (!effect.enabled) return;
  const double scale = ThermalScale(effect, t);
  for (std::size_t i = 0; i < ParameterCountOf(joint_count); ++i) {
    if (IsTranslationIndex(i, joint_count)) parameters[i] *= scale;
  }
}

double PlayOutput(double output, double input, double angle) {
  return std::clamp(output, input - 0.5 * angle, input + 0.5 * angle);
}

double IncidenceNoiseFactor(const IncidenceNoiseEffect& effect, double cos_incidence) {
  if (!effect.enabled) return 1;
  const double c = std::clamp(cos_incidence, 1e-6, 1.0);
  return std::min(effect.max_factor, std::pow(c, -effect.exponent));
}

bool LostAtGrazingAngle(const GrazingDropoutEffect& effect, double cos_incidence) {
  return effect.enabled && cos_incidence < std::cos(effect.max_angle);
}

std::vector<double> GravityDeflection(const JointElasticityEffect& effect,
                                      const std::vector<Eigen::Vector3d>& axes,
                                      const std::vector<Eigen::Vector3d>& origins,
                                      const Eigen::Vector3d& tool_point) {
  std::vector<double> deflection = GravityTorques(effect.link_masses, effect.sensor_mass,
                                                  JointFrames{axes, origins, tool_point});
  for (std::size_t j = 0; j < deflection.size(); ++j) deflection[j] /= effect.stiffness[j];
  return deflection;
}

double CastCapsule(const Capsule& capsule, const Eigen::Vector3d& origin,
                   const Eigen::Vector3d& direction, Eigen::Vector3d* normal) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const Eigen::Vector3d axis = capsule.b - capsule.a;
  const double length = axis.norm();
  const double r2 = capsule.radius * capsule.radius;
  auto distance_to_axis = [&](const Eigen::Vector3d& p) {
    const double s =
        length > 0 ? std::clamp((p - capsule.a).dot(axis) / (length * length), 0.0, 1.0) : 0.0;
    return capsule.a + s * axis;
  };
  if ((origin - distance_to_axis(origin)).squaredNorm() <= r2) return kInf;  // starts inside
  double best = kInf;
  Eigen::Vector3d best_normal = Eigen::Vector3d::Zero();
  // The cylinder between the caps.
  if (length > 0) {
    const Eigen::Vector3d u = axis / length;
    const Eigen::Vector3d w = origin - capsule.a;
    const Eigen::Vector3d d_perp = direction - direction.dot(u) * u;
    const Eigen::Vector3d w_perp = w - w.dot(u) * u;
    const double a = d_perp.squaredNorm(), b = 2 * d_perp.dot(w_perp),
                 c = w_perp.squaredNorm() - r2;
    const double disc = b * b - 4 * a * c;
    if (a > 1e-12 && disc >= 0) {
      const double t = (-b - std::sqrt(disc)) / (2 * a);
      const double s = (w + t * direction).dot(u);
      if (t > 0 && s >= 0 && s <= length) {
        best = t;
        best_normal = (w_perp + t * d_perp).normalized();
      }
    }
  }
  // The two spherical caps.
  for (const Eigen::Vector3d* centre : {&capsule.a, &capsule.b}) {
    const Eigen::Vector3d w = origin - *centre;
    const double b = w.dot(direction), c = w.squaredNorm() - r2;
    const double disc = b * b - c;
    if (disc < 0) continue;
    const double t = -b - std::sqrt(disc);
    if (t > 0 && t < best) {
      best = t;
      best_normal = (w + t * direction).normalized();
    }
  }
  if (normal && best < kInf) *normal = best_normal;
  return best;
}

double CastBox(const Eigen::AlignedBox3d& box, const Eigen::Vector3d& origin,
               const Eigen::Vector3d& direction, Eigen::Vector3d* normal) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (box.contains(origin)) return kInf;
  double t_near = -kInf, t_far = kInf;
  int axis_near = 0;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(direction[k]) < 1e-15) {
      if (origin[k] < box.min()[k] || origin[k] > box.max()[k]) return kInf;
      continue;
    }
    double t1 = (box.min()[k] - origin[k]) / direction[k];
    double t2 = (box.max()[k] - origin[k]) / direction[k];
    if (t1 > t2) std::swap(t1, t2);
    if (t1 > t_near) {
      t_near = t1;
      axis_near = k;
    }
    t_far = std::min(t_far, t2);
  }
  if (t_near > t_far || t_near <= 0) return kInf;
  if (normal) {
    *normal = Eigen::Vector3d::Zero();
    (*normal)[axis_near] = direction[axis_near] > 0 ? -1 : 1;
  }
  return t_near;
}

double DynamicGeometry::Cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                             double max_distance, Eigen::Vector3d* normal) const {
  double best = std::numeric_limits<double>::infinity();
  Eigen::Vector3d n;
  for (const auto& capsule : capsules) {
    const double t = CastCapsule(capsule, origin, direction, &n);
    if (t < best && t <= max_distance) {
      best = t;
      if (normal) *normal = n;
    }
  }
  for (const auto& box : boxes) {
    const double t = CastBox(box, origin, direction, &n);
    if (t < best && t <= max_distance) {
      best = t;
      if (normal) *normal = n;
    }
  }
  return best;
}

RayReturn CastFieldRay(const RayCaster& caster, const DynamicGeometry& geometry,
                       const FieldEffects& effects, const Eigen::Vector3d& origin,
                       const Eigen::Vector3d& direction, double reach) {
  RayCaster::Hit hit = caster.CastHit(origin, direction, reach);
  if (!geometry.empty()) {
    Eigen::Vector3d normal;
    const double d = geometry.Cast(origin, direction, std::min(hit.distance, reach), &normal);
    if (d < hit.distance) hit = {d, normal, 1.0};
  }
  RayReturn result;
  if (!std::isfinite(hit.distance)) return result;
  result.cosine = std::abs(hit.normal.dot(direction));
  result.albedo = hit.albedo;
  result.normal = hit.normal.dot(direction) > 0 ? Eigen::Vector3d(-hit.normal) : hit.normal;
  if (LostAtGrazingAngle(effects.grazing_dropout, result.cosine)) return result;
  result.distance = hit.distance;
  return result;
}

bool ShadowedFromSecondViewpoint(const RayCaster& caster, const DynamicGeometry& geometry,
                                 const BaselineShadowEffect& effect, SensorLayout layout,
                                 const Eigen::Isometry3d& T_base_sensor,
                                 const Eigen::Vector3d& point) {
  const double b = effect.baseline;
  const Eigen::Vector3d offset =
      layout == SensorLayout::kLineScanner ? Eigen::Vector3d(0, b, 0) : Eigen::Vector3d(b, 0, 0);
  const Eigen::Vector3d viewpoint = T_base_sensor * offset;
  const Eigen::Vector3d to_point = point - viewpoint;
  const double distance = to_point.norm();
  if (!(distance > 0)) return false;
  const Eigen::Vector3d direction = to_point / distance;
  // A tolerance of a millimetre keeps the surface itself from shadowing its own point.
  const double clear = distance - 1e-3;
  if (caster.Cast(viewpoint, direction, clear) < clear) return true;
  return geometry.Cast(viewpoint, direction, clear, nullptr) < clear;
}

namespace {

// Cosine-weighted directions on the unit hemisphere about +z (Fibonacci points on the disc,
// lifted): the same pattern for every hit, so the excess is smooth and free of noise.
Eigen::Vector3d HemisphereDirection(int k, int samples) {
  const double golden = std::numbers::pi * (3 - std::sqrt(5.0));
  const double r = std::sqrt((k + 0.5) / samples);
  const double phi = golden * k;
  return {r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0, 1 - r * r))};
}

}  // namespace

double MultipathExcess(const MultipathEffect& effect, const RayCaster& caster,
                       const DynamicGeometry& geometry, const Eigen::Vector3d& point,
                       const Eigen::Vector3d& normal) {
  if (!effect.enabled || effect.samples <= 0) return 0;
  // A tangent frame about the normal; the start lifted off the surface so it cannot see itself.
  const Eigen::Vector3d helper =
      std::abs(normal.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d t1 = normal.cross(helper).normalized();
  const Eigen::Vector3d t2 = normal.cross(t1);
  const Eigen::Vector3d start = point + 1e-4 * normal;
  double seen = 0;
  for (int k = 0; k < effect.samples; ++k) {
    const Eigen::Vector3d local = HemisphereDirection(k, effect.samples);
    const Eigen::Vector3d direction = local.x() * t1 + local.y() * t2 + local.z() * normal;
    const RayCaster::Hit hit = caster.CastHit(start, direction, effect.radius);
    if (std::isfinite(hit.distance)) {
      seen += hit.albedo;
    } else if (!geometry.empty() &&
               std::isfinite(geometry.Cast(start, direction, effect.radius, nullptr))) {
      seen += 1;
    }
  }
  return 2 * effect.amplitude * seen / effect.samples;
}

namespace {

// Node index and interpolation weight of grid coordinate x (0..size-1) between nodes every
// `step` (the last node at size - 1).
struct Bracket {
  int low, high;
  double weight;  // of `high`
};
Bracket BracketOf(int x, int size, int step) {
  const int low = std::min(x / step * step, size - 1);
  const int high = std::min(low + step, size - 1);
  return {low, high, high > low ? static_cast<double>(x - low) / (high - low) : 0.0};
}

}  // namespace

std::vector<double> MultipathGrid(const MultipathEffect& effect, const RayCaster& caster,
                                  const DynamicGeometry& geometry, int width, int height,
                                  const std::vector<Eigen::Vector3d>& points,
                                  const std::vector<Eigen::Vector3d>& normals,
                                  const std::vector<char>& valid, int step) {
  const std::size_t w = static_cast<std::size_t>(width);
  std::vector<double> excess(w * static_cast<std::size_t>(height), 0.0);
  if (!effect.enabled) return excess;
  auto index = [&](int u, int v) {
    return static_cast<std::size_t>(v) * w + static_cast<std::size_t>(u);
  };
  auto exact = [&](std::size_t i) {
    return valid[i] ? MultipathExcess(effect, caster, geometry, points[i], normals[i]) : 0.0;
  };
  auto is_node = [&](int x, int size) { return x % step == 0 || x == size - 1; };
  // The nodes first, then every other cell from them; each writes only its own slot.
  auto rows = [&](bool nodes) {
    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& r) {
      for (int v = r.begin(); v != r.end(); ++v) {
        for (int u = 0; u < width; ++u) {
          const bool node = is_node(u, width) && is_node(v, height);
          if (node != nodes) continue;
          const std::size_t i = index(u, v);
          if (node || !valid[i]) {
            excess[i] = exact(i);
            continue;
          }
          const Bracket bu = BracketOf(u, width, step), bv = BracketOf(v, height, step);
          const std::size_t corners[4] = {index(bu.low, bv.low), index(bu.high, bv.low),
                                          index(bu.low, bv.high), index(bu.high, bv.high)};
          const double weights[4] = {(1 - bu.weight) * (1 - bv.weight), bu.weight * (1 - bv.weight),
                                     (1 - bu.weight) * bv.weight, bu.weight * bv.weight};
          // Only the nodes on this cell's surface (across a crease or an edge they are not).
          double sum = 0, total = 0;
          for (int c = 0; c < 4; ++c) {
            const std::size_t n = corners[c];
            if (!valid[n] ||
                std::abs(normals[i].dot(points[n] - points[i])) >= effect.radius / 20) {
              continue;
            }
            const double weight = weights[c] + 1e-3;
            sum += weight * excess[n];
            total += weight;
          }
          excess[i] = total > 0 ? sum / total : exact(i);
        }
      }
    });
  };
  rows(true);
  rows(false);
  return excess;
}

double SystematicMeasure(const FieldEffects& effects, double measure, double cosine, double t,
                         double albedo) {
  double m = measure + RangeBias(effects.range_bias, measure, cosine, t, albedo);
  if (effects.intrinsics.enabled) {
    m = m * (1 + effects.intrinsics.depth_scale) + effects.intrinsics.range_offset;
  }
  return m;
}

void DeflectJoints(const JointElasticityEffect& effect, std::span<const JointType> joint_types,
                   const double* parameters, double* q) {
  if (!effect.enabled) return;
  const ArmFrames frames = ComputeArmFrames(joint_types, parameters, q);
  const std::vector<double> deflection =
      GravityDeflection(effect, frames.axes, frames.origins, frames.tool_point);
  for (std::size_t j = 0; j < deflection.size(); ++j) q[j] += deflection[j];
}

void AddSceneMotion(const FieldEffects& effects, int scan, double fraction,
                    DynamicGeometry& geometry) {
  const WalkerEffect& walker = effects.walker;
  if (walker.enabled &&
      std::find(walker.scans.begin(), walker.scans.end(), scan) != walker.scans.end()) {
    const Eigen::Vector3d foot =
        walker.from + std::clamp(fraction, 0.0, 1.0) * (walker.to - walker.from);
    const Eigen::Vector3d up(0, 0, 1);
    geometry.capsules.push_back(
        {foot + walker.radius * up, foot + (walker.height - walker.radius) * up, walker.radius});
  }
  const MovedObjectEffect& moved = effects.moved_object;
  if (moved.enabled) {
    Eigen::Vector3d bottom = moved.position;
    if (scan >= moved.after_scan) bottom += moved.shift;
    const Eigen::Vector3d half(moved.size.x() / 2, moved.size.y() / 2, 0);
    geometry.boxes.emplace_back(bottom - half,
                                bottom + half + Eigen::Vector3d(0, 0, moved.size.z()));
  }
}

}  // namespace selfcal::sim
