#include "protocols/scenario/effects_file.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "protocols/model_file/yaml_writer.h"

namespace selfcal {
namespace {

using yaml::Number;
using yaml::NumberList;
using yaml::StrictMap;

double InRange(StrictMap& map, const std::string& key, double fallback, double low, double high) {
  const double value = map.OptionalFinite(key, fallback);
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

// Reads the block `key` of `map`, when there, into `effect`, which its presence enables: `read`
// takes the block's keys, and any other key in it is an error.
template <typename Effect, typename Read>
void ReadEffect(StrictMap& map, const std::string& key, Effect& effect, Read read) {
  map.OptionalSection(key, [&](StrictMap& block) {
    effect.enabled = true;
    read(block, effect);
  });
}

// Reads `key` of `map` into `value` (kept when absent), which must lie in low..high.
void ReadInRange(StrictMap& map, const std::string& key, double& value, double low, double high) {
  value = InRange(map, key, value, low, high);
}

// The effects of surfaces beyond their geometry: other surfaces nearby, reflectivity, speckle.
void ReadSurfaceEffects(StrictMap& map, sim::FieldEffects& e) {
  ReadEffect(map, "multipath", e.multipath, [](StrictMap& m, auto& p) {
    ReadInRange(m, "amplitude", p.amplitude, 0, 0.1);
    ReadInRange(m, "radius", p.radius, 0.005, 1);
    p.samples = m.Optional<int>("samples", p.samples);
    if (p.samples < 1 || p.samples > 256) m.Fail("samples", "must be in 1..256");
  });
  ReadEffect(map, "dark_dropout", e.dark_dropout,
             [](StrictMap& m, auto& d) { ReadInRange(m, "threshold", d.threshold, 1e-7, 10); });
  ReadEffect(map, "speckle", e.speckle, [](StrictMap& m, auto& s) {
    ReadInRange(m, "correlation_length", s.correlation_length, 0.1, 100);
  });
}

void ReadSensorEffects(StrictMap& map, sim::FieldEffects& e) {
  ReadEffect(map, "mixed_pixels", e.mixed_pixels, [](StrictMap& m, auto& p) {
    ReadInRange(m, "probability", p.probability, 0, 1);
    ReadInRange(m, "min_jump", p.min_jump, 1e-4, 10);
  });
  ReadEffect(map, "range_bias", e.range_bias, [](StrictMap& m, auto& b) {
    ReadInRange(m, "offset", b.offset, -0.1, 0.1);
    ReadInRange(m, "per_metre", b.per_metre, -0.05, 0.05);
    ReadInRange(m, "incidence", b.incidence, -0.1, 0.1);
    ReadInRange(m, "warmup_offset", b.warmup_offset, -0.1, 0.1);
    ReadInRange(m, "warmup_time_constant", b.warmup_time_constant, 1, 1e5);
    ReadInRange(m, "reflectivity", b.reflectivity, -0.1, 0.1);
  });
  ReadEffect(map, "incidence_noise", e.incidence_noise, [](StrictMap& m, auto& n) {
    ReadInRange(m, "exponent", n.exponent, 0, 4);
    ReadInRange(m, "max_factor", n.max_factor, 1, 100);
  });
  ReadEffect(map, "grazing_dropout", e.grazing_dropout,
             [](StrictMap& m, auto& d) { ReadInRange(m, "max_angle", d.max_angle, 0.1, 1.5708); });
  ReadEffect(map, "baseline_shadows", e.baseline_shadows,
             [](StrictMap& m, auto& b) { ReadInRange(m, "baseline", b.baseline, -1, 1); });
  ReadEffect(map, "intrinsics", e.intrinsics, [](StrictMap& m, auto& i) {
    ReadInRange(m, "depth_scale", i.depth_scale, -0.1, 0.1);
    ReadInRange(m, "range_offset", i.range_offset, -0.1, 0.1);
    ReadInRange(m, "focal_scale", i.focal_scale, -0.1, 0.1);
  });
  ReadSurfaceEffects(map, e);
}

void ReadRobotEffects(StrictMap& map, sim::FieldEffects& e) {
  ReadEffect(map, "joint_elasticity", e.joint_elasticity, [](StrictMap& m, auto& j) {
    const sim::JointElasticityEffect defaults = IiwaElasticity();
    j.stiffness = Positives(m, "stiffness", defaults.stiffness);
    j.link_masses = Positives(m, "link_masses", defaults.link_masses);
    if (j.stiffness.size() != j.link_masses.size()) {
      m.Fail("link_masses", "must have one entry per joint, as stiffness has");
    }
    j.sensor_mass = InRange(m, "sensor_mass", defaults.sensor_mass, 0, 50);
  });
  ReadEffect(map, "timing", e.timing, [](StrictMap& m, auto& t) {
    ReadInRange(m, "joint_lag", t.joint_lag, 0, 0.02);
    ReadInRange(m, "clock_drift_ppm", t.clock_drift_ppm, -500, 500);
  });
  ReadEffect(map, "thermal_growth", e.thermal_growth, [](StrictMap& m, auto& t) {
    ReadInRange(m, "expansion", t.expansion, 0, 1e-4);
    ReadInRange(m, "temperature_rise", t.temperature_rise, -50, 50);
    ReadInRange(m, "time_constant", t.time_constant, 1, 1e5);
  });
  ReadEffect(map, "backlash", e.backlash,
             [](StrictMap& m, auto& b) { ReadInRange(m, "angle", b.angle, 0, 0.05); });
}

void ReadSceneEffects(StrictMap& map, sim::FieldEffects& e) {
  ReadEffect(map, "self_view", e.self_view,
             [](StrictMap& m, auto& v) { ReadInRange(m, "radius", v.radius, 0.01, 0.3); });
  ReadEffect(map, "walker", e.walker, [](StrictMap& m, auto& w) {
    w.scans = m.Required<std::vector<int>>("scans");
    for (int scan : w.scans) {
      if (scan < 0) m.Fail("scans", "must be scan indices >= 0");
    }
    w.from = Vector3(m, "from", w.from);
    w.to = Vector3(m, "to", w.to);
    ReadInRange(m, "radius", w.radius, 0.05, 1);
    ReadInRange(m, "height", w.height, 2 * w.radius, 3);
  });
  ReadEffect(map, "moved_object", e.moved_object, [](StrictMap& m, auto& o) {
    o.after_scan = m.Required<int>("after_scan");
    if (o.after_scan < 0) m.Fail("after_scan", "must be a scan index >= 0");
    o.size = Vector3(m, "size", o.size);
    if (!(o.size.minCoeff() > 0)) m.Fail("size", "must be positive");
    o.position = Vector3(m, "position", o.position);
    o.shift = Vector3(m, "shift", o.shift);
  });
}

std::string Triple(const Eigen::Vector3d& v) { return NumberList({v.x(), v.y(), v.z()}); }

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
    out << "  joint_elasticity: {stiffness: " << NumberList(j.stiffness)
        << ", link_masses: " << NumberList(j.link_masses)
        << ", sensor_mass: " << Number(j.sensor_mass) << "}\n";
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
