#include "protocols/scenario/effects_file.h"

#include <cmath>
#include <cstdio>
#include <sstream>

namespace selfcal {
namespace {

using yaml::StrictMap;

double Finite(StrictMap& map, const std::string& key, double fallback) {
  const double value = map.Optional<double>(key, fallback);
  if (!std::isfinite(value)) map.Fail(key, "must be a finite number");
  return value;
}

double InRange(StrictMap& map, const std::string& key, double fallback, double low, double high) {
  const double value = Finite(map, key, fallback);
  if (!(value >= low && value <= high)) {
    map.Fail(key, "must be in " + std::to_string(low) + ".." + std::to_string(high));
  }
  return value;
}

Eigen::Vector3d Vector3(StrictMap& map, const std::string& key, const Eigen::Vector3d& fallback) {
  if (!map.Has(key)) return fallback;
  const auto values = map.Required<std::vector<double>>(key);
  if (values.size() != 3) map.Fail(key, "must have 3 entries [x, y, z]");
  for (double v : values) {
    if (!std::isfinite(v)) map.Fail(key, "must be finite");
  }
  return {values[0], values[1], values[2]};
}

std::vector<double> Positives(StrictMap& map, const std::string& key,
                              const std::vector<double>& fallback) {
  const auto values = map.Optional<std::vector<double>>(key, fallback);
  for (double v : values) {
    if (!(v > 0) || !std::isfinite(v)) map.Fail(key, "must hold finite numbers > 0");
  }
  return values;
}

// The effects of surfaces beyond their geometry: other surfaces nearby, reflectivity, speckle.
void ReadSurfaceEffects(StrictMap& map, sim::FieldEffects& e) {
  if (map.Has("multipath")) {
    StrictMap m = map.Map("multipath");
    auto& p = e.multipath;
    p.enabled = true;
    p.amplitude = InRange(m, "amplitude", p.amplitude, 0, 0.1);
    p.radius = InRange(m, "radius", p.radius, 0.005, 1);
    p.samples = m.Optional<int>("samples", p.samples);
    if (p.samples < 1 || p.samples > 256) m.Fail("samples", "must be in 1..256");
    m.RejectUnknownKeys();
  }
  if (map.Has("dark_dropout")) {
    StrictMap m = map.Map("dark_dropout");
    e.dark_dropout.enabled = true;
    e.dark_dropout.threshold = InRange(m, "threshold", e.dark_dropout.threshold, 1e-7, 10);
    m.RejectUnknownKeys();
  }
  if (map.Has("speckle")) {
    StrictMap m = map.Map("speckle");
    e.speckle.enabled = true;
    e.speckle.correlation_length =
        InRange(m, "correlation_length", e.speckle.correlation_length, 0.1, 100);
    m.RejectUnknownKeys();
  }
}

void ReadSensorEffects(StrictMap& map, sim::FieldEffects& e) {
  if (map.Has("mixed_pixels")) {
    StrictMap m = map.Map("mixed_pixels");
    e.mixed_pixels.enabled = true;
    e.mixed_pixels.probability = InRange(m, "probability", e.mixed_pixels.probability, 0, 1);
    e.mixed_pixels.min_jump = InRange(m, "min_jump", e.mixed_pixels.min_jump, 1e-4, 10);
    m.RejectUnknownKeys();
  }
  if (map.Has("range_bias")) {
    StrictMap m = map.Map("range_bias");
    auto& b = e.range_bias;
    b.enabled = true;
    b.offset = InRange(m, "offset", b.offset, -0.1, 0.1);
    b.per_metre = InRange(m, "per_metre", b.per_metre, -0.05, 0.05);
    b.incidence = InRange(m, "incidence", b.incidence, -0.1, 0.1);
    b.warmup_offset = InRange(m, "warmup_offset", b.warmup_offset, -0.1, 0.1);
    b.warmup_time_constant = InRange(m, "warmup_time_constant", b.warmup_time_constant, 1, 1e5);
    b.reflectivity = InRange(m, "reflectivity", b.reflectivity, -0.1, 0.1);
    m.RejectUnknownKeys();
  }
  if (map.Has("incidence_noise")) {
    StrictMap m = map.Map("incidence_noise");
    e.incidence_noise.enabled = true;
    e.incidence_noise.exponent = InRange(m, "exponent", e.incidence_noise.exponent, 0, 4);
    e.incidence_noise.max_factor = InRange(m, "max_factor", e.incidence_noise.max_factor, 1, 100);
    m.RejectUnknownKeys();
  }
  if (map.Has("grazing_dropout")) {
    StrictMap m = map.Map("grazing_dropout");
    e.grazing_dropout.enabled = true;
    e.grazing_dropout.max_angle = InRange(m, "max_angle", e.grazing_dropout.max_angle, 0.1, 1.5708);
    m.RejectUnknownKeys();
  }
  if (map.Has("baseline_shadows")) {
    StrictMap m = map.Map("baseline_shadows");
    e.baseline_shadows.enabled = true;
    e.baseline_shadows.baseline = InRange(m, "baseline", e.baseline_shadows.baseline, -1, 1);
    m.RejectUnknownKeys();
  }
  if (map.Has("intrinsics")) {
    StrictMap m = map.Map("intrinsics");
    auto& i = e.intrinsics;
    i.enabled = true;
    i.depth_scale = InRange(m, "depth_scale", i.depth_scale, -0.1, 0.1);
    i.range_offset = InRange(m, "range_offset", i.range_offset, -0.1, 0.1);
    i.focal_scale = InRange(m, "focal_scale", i.focal_scale, -0.1, 0.1);
    m.RejectUnknownKeys();
  }
  ReadSurfaceEffects(map, e);
}

void ReadRobotEffects(StrictMap& map, sim::FieldEffects& e) {
  if (map.Has("joint_elasticity")) {
    StrictMap m = map.Map("joint_elasticity");
    const sim::JointElasticityEffect defaults = IiwaElasticity();
    auto& j = e.joint_elasticity;
    j.enabled = true;
    j.stiffness = Positives(m, "stiffness", defaults.stiffness);
    j.link_masses = Positives(m, "link_masses", defaults.link_masses);
    if (j.stiffness.size() != j.link_masses.size()) {
      m.Fail("link_masses", "must have one entry per joint, as stiffness has");
    }
    j.sensor_mass = InRange(m, "sensor_mass", defaults.sensor_mass, 0, 50);
    m.RejectUnknownKeys();
  }
  if (map.Has("timing")) {
    StrictMap m = map.Map("timing");
    e.timing.enabled = true;
    e.timing.joint_lag = InRange(m, "joint_lag", e.timing.joint_lag, 0, 0.02);
    e.timing.clock_drift_ppm = InRange(m, "clock_drift_ppm", e.timing.clock_drift_ppm, -500, 500);
    m.RejectUnknownKeys();
  }
  if (map.Has("thermal_growth")) {
    StrictMap m = map.Map("thermal_growth");
    auto& t = e.thermal_growth;
    t.enabled = true;
    t.expansion = InRange(m, "expansion", t.expansion, 0, 1e-4);
    t.temperature_rise = InRange(m, "temperature_rise", t.temperature_rise, -50, 50);
    t.time_constant = InRange(m, "time_constant", t.time_constant, 1, 1e5);
    m.RejectUnknownKeys();
  }
  if (map.Has("backlash")) {
    StrictMap m = map.Map("backlash");
    e.backlash.enabled = true;
    e.backlash.angle = InRange(m, "angle", e.backlash.angle, 0, 0.05);
    m.RejectUnknownKeys();
  }
}

void ReadSceneEffects(StrictMap& map, sim::FieldEffects& e) {
  if (map.Has("self_view")) {
    StrictMap m = map.Map("self_view");
    e.self_view.enabled = true;
    e.self_view.radius = InRange(m, "radius", e.self_view.radius, 0.01, 0.3);
    m.RejectUnknownKeys();
  }
  if (map.Has("walker")) {
    StrictMap m = map.Map("walker");
    auto& w = e.walker;
    w.enabled = true;
    w.scans = m.Required<std::vector<int>>("scans");
    for (int scan : w.scans) {
      if (scan < 0) m.Fail("scans", "must be scan indices >= 0");
    }
    w.from = Vector3(m, "from", w.from);
    w.to = Vector3(m, "to", w.to);
    w.radius = InRange(m, "radius", w.radius, 0.05, 1);
    w.height = InRange(m, "height", w.height, 2 * w.radius, 3);
    m.RejectUnknownKeys();
  }
  if (map.Has("moved_object")) {
    StrictMap m = map.Map("moved_object");
    auto& o = e.moved_object;
    o.enabled = true;
    o.after_scan = m.Required<int>("after_scan");
    if (o.after_scan < 0) m.Fail("after_scan", "must be a scan index >= 0");
    o.size = Vector3(m, "size", o.size);
    if (!(o.size.minCoeff() > 0)) m.Fail("size", "must be positive");
    o.position = Vector3(m, "position", o.position);
    o.shift = Vector3(m, "shift", o.shift);
    m.RejectUnknownKeys();
  }
}

std::string Number(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  return buffer;
}

std::string List(const std::vector<double>& values) {
  std::ostringstream out;
  out << '[';
  for (std::size_t i = 0; i < values.size(); ++i) out << (i ? ", " : "") << Number(values[i]);
  out << ']';
  return out.str();
}

std::string Triple(const Eigen::Vector3d& v) { return List({v.x(), v.y(), v.z()}); }

}  // namespace

sim::JointElasticityEffect IiwaElasticity() {
  sim::JointElasticityEffect effect;
  effect.stiffness = {2.0e4, 2.0e4, 2.0e4, 2.0e4, 1.0e4, 1.0e4, 1.0e4};
  effect.link_masses = {5.76, 6.35, 3.5, 3.5, 3.5, 1.8, 1.2};
  effect.sensor_mass = 0.5;
  return effect;
}

void ReadEffects(StrictMap map, sim::FieldEffects& effects) {
  ReadSensorEffects(map, effects);
  ReadRobotEffects(map, effects);
  ReadSceneEffects(map, effects);
  map.RejectUnknownKeys();
}

std::string FormatEffects(const sim::FieldEffects& e) {
  if (!e.AnyEnabled()) return {};
  std::ostringstream out;
  out << "effects:\n";
  if (e.mixed_pixels.enabled) {
    out << "  mixed_pixels: {probability: " << Number(e.mixed_pixels.probability)
        << ", min_jump: " << Number(e.mixed_pixels.min_jump) << "}\n";
  }
  if (const auto& b = e.range_bias; b.enabled) {
    out << "  range_bias: {offset: " << Number(b.offset) << ", per_metre: " << Number(b.per_metre)
        << ", incidence: " << Number(b.incidence) << ", warmup_offset: " << Number(b.warmup_offset)
        << ", warmup_time_constant: " << Number(b.warmup_time_constant)
        << ", reflectivity: " << Number(b.reflectivity) << "}\n";
  }
  if (e.incidence_noise.enabled) {
    out << "  incidence_noise: {exponent: " << Number(e.incidence_noise.exponent)
        << ", max_factor: " << Number(e.incidence_noise.max_factor) << "}\n";
  }
  if (e.grazing_dropout.enabled) {
    out << "  grazing_dropout: {max_angle: " << Number(e.grazing_dropout.max_angle) << "}\n";
  }
  if (e.baseline_shadows.enabled) {
    out << "  baseline_shadows: {baseline: " << Number(e.baseline_shadows.baseline) << "}\n";
  }
  if (const auto& i = e.intrinsics; i.enabled) {
    out << "  intrinsics: {depth_scale: " << Number(i.depth_scale)
        << ", range_offset: " << Number(i.range_offset)
        << ", focal_scale: " << Number(i.focal_scale) << "}\n";
  }
  if (const auto& j = e.joint_elasticity; j.enabled) {
    out << "  joint_elasticity: {stiffness: " << List(j.stiffness)
        << ", link_masses: " << List(j.link_masses) << ", sensor_mass: " << Number(j.sensor_mass)
        << "}\n";
  }
  if (e.timing.enabled) {
    out << "  timing: {joint_lag: " << Number(e.timing.joint_lag)
        << ", clock_drift_ppm: " << Number(e.timing.clock_drift_ppm) << "}\n";
  }
  if (const auto& t = e.thermal_growth; t.enabled) {
    out << "  thermal_growth: {expansion: " << Number(t.expansion)
        << ", temperature_rise: " << Number(t.temperature_rise)
        << ", time_constant: " << Number(t.time_constant) << "}\n";
  }
  if (e.backlash.enabled) out << "  backlash: {angle: " << Number(e.backlash.angle) << "}\n";
  if (const auto& p = e.multipath; p.enabled) {
    out << "  multipath: {amplitude: " << Number(p.amplitude) << ", radius: " << Number(p.radius)
        << ", samples: " << p.samples << "}\n";
  }
  if (e.dark_dropout.enabled) {
    out << "  dark_dropout: {threshold: " << Number(e.dark_dropout.threshold) << "}\n";
  }
  if (e.speckle.enabled) {
    out << "  speckle: {correlation_length: " << Number(e.speckle.correlation_length) << "}\n";
  }
  if (e.self_view.enabled) out << "  self_view: {radius: " << Number(e.self_view.radius) << "}\n";
  if (const auto& w = e.walker; w.enabled) {
    out << "  walker: {scans: [";
    for (std::size_t i = 0; i < w.scans.size(); ++i) out << (i ? ", " : "") << w.scans[i];
    out << "], from: " << Triple(w.from) << ", to: " << Triple(w.to)
        << ", radius: " << Number(w.radius) << ", height: " << Number(w.height) << "}\n";
  }
  if (const auto& o = e.moved_object; o.enabled) {
    out << "  moved_object: {after_scan: " << o.after_scan << ", size: " << Triple(o.size)
        << ", position: " << Triple(o.position) << ", shift: " << Triple(o.shift) << "}\n";
  }
  return out.str();
}

}  // namespace selfcal
