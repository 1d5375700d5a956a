#include "protocols/model_file/sensor_config.h"

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

SensorConfig ReadDocument(const YAML::Node& root, const std::string& name) {
  SensorConfig config;
  StrictMap map(root, "", name);
  config.name = map.Required<std::string>("name");
  const auto layout = map.Required<std::string>("layout");
  if (layout == "rotating_lidar") {
    config.layout = SensorLayout::kRotatingLidar;
  } else if (layout == "line_scanner") {
    config.layout = SensorLayout::kLineScanner;
  } else if (layout == "depth_camera") {
    config.layout = SensorLayout::kDepthCamera;
  } else {
    map.Fail("layout",
             "must be rotating_lidar, line_scanner or depth_camera, not '" + layout + "'");
  }
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
    if (config.sigma_abs < 0 || config.sigma_rel < 0) m.Fail("sigma_abs", "must not be negative");
    m.RejectUnknownKeys();
  }
  {
    StrictMap m = map.Map("preprocessing");
    config.filter_n = m.Required<int>("n");
    config.filter_m = m.Required<int>("m");
    if (config.filter_n < 0 || config.filter_m < 0)
      m.Fail("n", "window radii must not be negative");
    config.g_min = m.Required<double>("g_min");
    m.RejectUnknownKeys();
  }
  {
    StrictMap m = map.Map("match_validation");
    config.d_max = Positive(m, "d_max");
    config.f_min = m.Required<double>("f_min");
    // Not in Table I (docs/engine.md, deviation 11): query every s-th row and column of Q_i.
    config.query_stride = m.Optional<int>("query_stride", 1);
    if (config.query_stride < 1) m.Fail("query_stride", "must be at least 1");
    m.RejectUnknownKeys();
  }
  {
    StrictMap m = map.Map("stop");
    config.epsilon = Positive(m, "epsilon");
    config.i_max = PositiveInt(m, "i_max");
    m.RejectUnknownKeys();
  }
  ReadGeometry(map.Map("geometry"), config);
  map.RejectUnknownKeys();
  return config;
}

}  // namespace

const char* LayoutName(SensorLayout layout) {
  switch (layout) {
    case SensorLayout::kRotatingLidar:
      return "rotating_lidar";
    case SensorLayout::kLineScanner:
      return "line_scanner";
    case SensorLayout::kDepthCamera:
      return "depth_camera";
  }
  return "unknown";
}

Expected<SensorConfig> ParseSensorConfig(const std::string& text, const std::string& name) {
  return yaml::Catching<SensorConfig>(
      [&] { return ReadDocument(yaml::LoadString(text, name), name); });
}

Expected<SensorConfig> ReadSensorConfig(const std::string& path) {
  return yaml::Catching<SensorConfig>([&] { return ReadDocument(yaml::LoadFile(path), path); });
}

}  // namespace selfcal
