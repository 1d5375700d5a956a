#include "protocols/model_file/sensor_config.h"

#include <cmath>

#include "core/calib/intrinsics_choice.h"
#include "core/calib/parameter_limits.h"
#include "protocols/model_file/yaml_reader.h"

namespace selfcal {
namespace {

using yaml::StrictMap;

double Positive(StrictMap& map, const std::string& key) {
  const auto value = map.Required<double>(key);
  if (!(value > 0)) map.Fail(key, "must be positive");
  return value;
}

int PositiveInt(StrictMap& map, const std::string& key) {
  const auto value = map.Required<int>(key);
  if (value <= 0) map.Fail(key, "must be positive");
  return value;
}

// A Table I value, within the engine's limit for it (core/calib/parameter_limits.h).
template <typename T>
T Limited(StrictMap& map, const std::string& key, const calib::ParameterLimit& limit) {
  const auto value = map.Required<T>(key);
  if (!limit.allows(static_cast<double>(value))) {
    map.Fail(key, std::string("must be ") + limit.requirement);
  }
  return value;
}

void ReadGeometry(StrictMap map, SensorConfig& config) {
  switch (config.layout) {
    case SensorLayout::kRotatingLidar:
      config.lidar.steps = PositiveInt(map, "steps");
      config.lidar.angle_first = map.Required<double>("angle_first");
      config.lidar.angle_increment = Positive(map, "angle_increment");
      config.lidar.rotation_rate_hz = Positive(map, "rotation_rate_hz");
      config.lidar.steps_per_rotation = PositiveInt(map, "steps_per_rotation");
      break;
    case SensorLayout::kLineScanner:
      config.line.points = PositiveInt(map, "points");
      config.line.fan_angle = Positive(map, "fan_angle");
      config.line.line_rate_hz = Positive(map, "line_rate_hz");
      break;
    case SensorLayout::kDepthCamera:
      config.camera.intrinsics.fx = Positive(map, "fx");
      config.camera.intrinsics.fy = Positive(map, "fy");
      config.camera.intrinsics.cx = map.Required<double>("cx");
      config.camera.intrinsics.cy = map.Required<double>("cy");
      config.camera.frame_rate_hz = Positive(map, "frame_rate_hz");
      break;
  }
  map.RejectUnknownKeys();
}

// The sections beyond the paper's Table I that the engine reads: the latency (deviation 16),
// which intrinsics it calibrates (deviation 17) and the uncertainty of those it holds
// (deviation 21).
void ReadBeyondTableOne(StrictMap& map, SensorConfig& config) {
  if (map.Has("calibrate_intrinsics")) {
    config.calibrate_intrinsics = map.Required<std::string>("calibrate_intrinsics");
    calib::IntrinsicsChoice unused;
    if (std::string problem = calib::ParseIntrinsicsChoice(config.calibrate_intrinsics, &unused);
        !problem.empty())
      map.Fail("calibrate_intrinsics", problem);
  }
  map.OptionalSection("latency", [&config](StrictMap& m) {
    config.latency_s = m.OptionalFinite("seconds", 0.0);
    if (!calib::kLatencyLimit.allows(config.latency_s))
      m.Fail("seconds", std::string("must be ") + calib::kLatencyLimit.requirement);
    if (m.Has("estimate")) config.estimate_latency = m.Required<bool>("estimate");
  });
  map.OptionalSection("intrinsics_uncertainty", [&config](StrictMap& m) {
    auto& u = config.intrinsics_uncertainty;
    for (auto [key, value] : {std::pair{"scale", &u.scale}, std::pair{"offset", &u.offset_m},
                              std::pair{"focal", &u.focal}}) {
      *value = m.OptionalFinite(key, 0.0);
      if (!calib::kIntrinsicSdLimit.allows(*value))
        m.Fail(key, std::string("must be ") + calib::kIntrinsicSdLimit.requirement);
    }
  });
}

SensorConfig ReadDocument(StrictMap& map) {
  SensorConfig config;
  config.name = map.Required<std::string>("name");
  config.layout = map.RequiredChoice("layout", kSensorLayoutNames);
  {
    StrictMap m = map.Map("resolution");
    config.resolution_x = PositiveInt(m, "x");
    config.resolution_y = PositiveInt(m, "y");
    m.RejectUnknownKeys();
  }
  {
    StrictMap m = map.Map("view_range");
    config.range_closest = Positive(m, "closest");
    config.range_farthest = Positive(m, "farthest");
    if (config.range_farthest <= config.range_closest) m.Fail("farthest", "must exceed 'closest'");
    m.RejectUnknownKeys();
  }
  {
    StrictMap m = map.Map("noise");
    config.sigma_abs = m.Required<double>("sigma_abs");
    config.sigma_rel = m.Required<double>("sigma_rel");
    if (!(config.sigma_abs >= 0) || !std::isfinite(config.sigma_abs)) {
      m.Fail("sigma_abs", "must be a finite number, not negative");
    }
    if (!(config.sigma_rel >= 0) || !std::isfinite(config.sigma_rel)) {
      m.Fail("sigma_rel", "must be a finite number, not negative");
    }
    m.RejectUnknownKeys();
  }
  {
    StrictMap m = map.Map("preprocessing");
    config.filter_n = Limited<int>(m, "n", calib::kFilterRadiusLimit);
    config.filter_m = Limited<int>(m, "m", calib::kFilterRadiusLimit);
    config.g_min = Limited<double>(m, "g_min", calib::kGMinLimit);
    // Not in Table I (docs/engine.md, deviation 19): the flying pixel angle [deg], 0 = off.
    config.flying_pixel_angle_deg = m.Optional<double>("flying_pixel_angle", 0.0);
    if (!calib::kFlyingPixelAngleLimit.allows(config.flying_pixel_angle_deg)) {
      m.Fail("flying_pixel_angle",
             std::string("must be ") + calib::kFlyingPixelAngleLimit.requirement);
    }
    m.RejectUnknownKeys();
  }
  {
    StrictMap m = map.Map("match_validation");
    config.d_max = Limited<double>(m, "d_max", calib::kDMaxLimit);
    config.f_min = Limited<double>(m, "f_min", calib::kFMinLimit);
    // Not in Table I (docs/engine.md, deviation 11): query every s-th row and column of Q_i.
    config.query_stride = m.Optional<int>("query_stride", 1);
    if (!calib::kQueryStrideLimit.allows(config.query_stride)) {
      m.Fail("query_stride", std::string("must be ") + calib::kQueryStrideLimit.requirement);
    }
    // Not in the paper (docs/engine.md, deviation 24): coarse to fine from this stride.
    config.coarse_stride = m.Optional<int>("coarse_stride", 1);
    if (!calib::kQueryStrideLimit.allows(config.coarse_stride)) {
      m.Fail("coarse_stride", std::string("must be ") + calib::kQueryStrideLimit.requirement);
    }
    // Not in the paper (docs/engine.md, deviations 10 and 12); empty = the layout's.
    config.border_rule = m.Optional<std::string>("border_rule", "");
    if (!config.border_rule.empty() && config.border_rule != "off" &&
        config.border_rule != "exact" && config.border_rule != "surface") {
      m.Fail("border_rule", "must be off, exact or surface");
    }
    m.RejectUnknownKeys();
  }
  {
    StrictMap m = map.Map("stop");
    config.epsilon = Limited<double>(m, "epsilon", calib::kEpsilonLimit);
    config.i_max = Limited<int>(m, "i_max", calib::kIMaxLimit);
    m.RejectUnknownKeys();
  }
  config.mass = map.Optional<double>("mass_kg", 0.0);  // joint elasticity's sensor load
  if (!(config.mass >= 0) || !std::isfinite(config.mass))
    map.Fail("mass_kg", "must be a finite number, not negative");
  ReadBeyondTableOne(map, config);
  ReadGeometry(map.Map("geometry"), config);
  return config;
}

}  // namespace

Expected<SensorConfig> ParseSensorConfig(const std::string& text, const std::string& name) {
  return yaml::ParseDocument<SensorConfig>(text, name, ReadDocument);
}

Expected<SensorConfig> ReadSensorConfig(const std::string& path) {
  return yaml::ReadDocumentFile<SensorConfig>(path, ReadDocument);
}

}  // namespace selfcal
