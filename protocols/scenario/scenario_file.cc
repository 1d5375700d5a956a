#include "protocols/scenario/scenario_file.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "protocols/model_file/yaml_reader.h"
#include "protocols/model_file/yaml_writer.h"
#include "protocols/scenario/effects_file.h"

namespace selfcal {
namespace {

using yaml::Number;
using yaml::StrictMap;
using yaml::Text;
using SceneKind = sim::SceneSpec::Kind;
using SceneObject = sim::SceneSpec::Object;
using PlanKind = sim::PlanOptions::Kind;

std::string Resolve(const std::string& path, const std::string& directory) {
  std::filesystem::path p(path);
  if (p.is_relative()) p = std::filesystem::path(directory) / p;
  return p.lexically_normal().string();
}

// [low, high] with low <= high.
void ReadRange(StrictMap& map, const std::string& key, double& low, double& high) {
  if (!map.Has(key)) {
    map.Raw(key);
    return;
  }
  const auto values = map.Required<std::vector<double>>(key);
  if (values.size() != 2) map.Fail(key, "must be a pair [low, high]");
  if (!std::isfinite(values[0]) || !std::isfinite(values[1])) map.Fail(key, "must be finite");
  if (!(values[0] <= values[1])) map.Fail(key, "must be ordered: low <= high");
  low = values[0];
  high = values[1];
}

Eigen::Vector3d ReadVector3(StrictMap& map, const std::string& key) {
  const auto values = map.Required<std::vector<double>>(key);
  if (values.size() != 3) map.Fail(key, "must have 3 entries [x, y, z]");
  for (const double value : values) {
    if (!std::isfinite(value)) map.Fail(key, "must be finite");
  }
  return {values[0], values[1], values[2]};
}

double NonNegative(StrictMap& map, const std::string& key, double fallback) {
  const double value = map.Optional<double>(key, fallback);
  if (!(value >= 0) || !std::isfinite(value)) map.Fail(key, "must be a finite number >= 0");
  return value;
}

double Positive(StrictMap& map, const std::string& key, double fallback) {
  const double value = map.Optional<double>(key, fallback);
  if (!(value > 0) || !std::isfinite(value)) map.Fail(key, "must be a finite number > 0");
  return value;
}

// The scenario files' spelling of each choice, read here and written by FormatScenario.
constexpr EnumNames<SceneKind, 5> kSceneKinds{{
    {SceneKind::kTabletop, "tabletop"},
    {SceneKind::kOffice, "office"},
    {SceneKind::kLab, "lab"},
    {SceneKind::kCorner, "corner"},
    {SceneKind::kCell, "cell"},
}};
constexpr EnumNames<SceneObject, 3> kSceneObjects{{
    {SceneObject::kBunny, "bunny"},
    {SceneObject::kTeapot, "teapot"},
    {SceneObject::kNone, "none"},
}};

// `{min: [x, y, z], max: [x, y, z]}`, min below max on every axis.
Eigen::AlignedBox3d ReadBox(StrictMap map) {
  const Eigen::Vector3d min = ReadVector3(map, "min");
  const Eigen::Vector3d max = ReadVector3(map, "max");
  if (!(min.array() < max.array()).all()) map.Fail("max", "must be above min on every axis");
  map.RejectUnknownKeys();
  return {min, max};
}

void ReadCell(StrictMap& map, sim::SceneSpec& scene) {
  scene.cell_free_space = ReadBox(map.Map("free_space"));
  const auto obstacles = map.Sequence("obstacles", /*required=*/false);
  for (std::size_t i = 0; i < obstacles.size(); ++i) {
    const std::string path = map.PathOf("obstacles") + "[" + std::to_string(i) + "]";
    scene.cell_obstacles.push_back(ReadBox(StrictMap(obstacles[i], path, map.file())));
  }
}

void ReadScene(StrictMap map, sim::SceneSpec& scene, const std::string& directory) {
  scene.kind = map.RequiredChoice("kind", kSceneKinds);
  if (scene.kind == SceneKind::kCell) ReadCell(map, scene);
  if (scene.kind == SceneKind::kTabletop) {
    scene.object = map.RequiredChoice("object", kSceneObjects);
    if (scene.object == SceneObject::kBunny) {
      scene.bunny_path = Resolve(
          map.Optional<std::string>("mesh", "/usr/share/glmark2/models/bunny.obj"), directory);
    }
    scene.object_size = Positive(map, "object_size", scene.object_size);
    if (map.Has("object_position")) scene.object_position = ReadVector3(map, "object_position");
    scene.object_yaw = map.OptionalFinite("object_yaw", 0.0);
  }
  if (map.Has("albedo")) {
    // Reflectivity per part of the scene (core/sim/scene.h), 1 where not given.
    StrictMap albedo = map.Map("albedo");
    for (const char* part : {"object", "furniture", "room"}) {
      if (!albedo.Has(part)) continue;
      const double value = albedo.Required<double>(part);
      if (!(value > 0 && value <= 1)) albedo.Fail(part, "must be in (0, 1]");
      scene.albedo.emplace_back(part, value);
    }
    albedo.RejectUnknownKeys();
  }
  map.RejectUnknownKeys();
}

void ReadView(StrictMap map, sim::ViewOptions& view, bool& target_given) {
  target_given = map.Has("target");
  if (target_given) view.target = ReadVector3(map, "target");
  view.target_jitter = NonNegative(map, "target_jitter", view.target_jitter);
  ReadRange(map, "distance", view.distance_min, view.distance_max);
  ReadRange(map, "elevation", view.elevation_min, view.elevation_max);
  ReadRange(map, "azimuth", view.azimuth_min, view.azimuth_max);
  ReadRange(map, "roll", view.roll_min, view.roll_max);
  if (!(view.distance_min > 0)) map.Fail("distance", "must be positive");
  if (view.elevation_max > 1.5)
    map.Fail("elevation", "must stay below 1.5 rad (straight down is degenerate)");
  map.RejectUnknownKeys();
}

constexpr EnumNames<PlanKind, 3> kPlanKinds{{
    {PlanKind::kStationaryViews, "stationary_views"},
    {PlanKind::kLineSweeps, "line_sweeps"},
    {PlanKind::kLidarSweeps, "lidar_sweeps"},
}};

void ReadPlan(StrictMap map, Scenario& scenario) {
  sim::PlanOptions& plan = scenario.plan;
  plan.kind = map.RequiredChoice("kind", kPlanKinds);
  plan.fit_scans = map.Required<int>("scans");
  if (plan.fit_scans < 1 || plan.fit_scans > 1000) map.Fail("scans", "must be in 1..1000");
  plan.validation_scans = map.Optional<int>("validation_scans", 7);
  if (plan.validation_scans < 0 || plan.validation_scans > 1000)
    map.Fail("validation_scans", "must be in 0..1000");
  plan.free_margin = NonNegative(map, "free_margin", plan.free_margin);
  plan.limit_margin = NonNegative(map, "limit_margin", plan.limit_margin);
  plan.link_radius = NonNegative(map, "link_radius", plan.link_radius);
  if (plan.link_radius > 0.5) map.Fail("link_radius", "must be at most 0.5 m");
  plan.max_attempts = map.Optional<int>("max_attempts", plan.max_attempts);
  if (plan.max_attempts < 1) map.Fail("max_attempts", "must be positive");
  if (plan.kind != PlanKind::kLidarSweeps) {
    ReadView(map.Map("view"), plan.view, scenario.view_target_given);
  }
  if (plan.kind == PlanKind::kLineSweeps) {
    plan.sweep_length = Positive(map, "sweep_length", plan.sweep_length);
    plan.sweep_speed = Positive(map, "sweep_speed", plan.sweep_speed);
  }
  if (plan.kind == PlanKind::kLidarSweeps) {
    plan.sweep_angle = Positive(map, "sweep_angle", plan.sweep_angle);
    scenario.lidar_line_spacing = Positive(map, "line_spacing", scenario.lidar_line_spacing);
  }
  map.RejectUnknownKeys();
}

constexpr EnumNames<CameraOutput, 2> kCameraOutputs{{
    {CameraOutput::kDepthImage, "depth_image"},
    {CameraOutput::kOrganizedCloud, "organized_cloud"},
}};

Scenario ReadDocument(StrictMap& map, const std::string& directory) {
  Scenario scenario;
  scenario.name = map.Required<std::string>("name");
  scenario.seed = map.Required<std::uint64_t>("seed");
  scenario.start_utime = map.Optional<std::int64_t>("start_utime", scenario.start_utime);
  if (scenario.start_utime < 0) map.Fail("start_utime", "must not be negative");
  scenario.robot_path = Resolve(map.Required<std::string>("robot"), directory);
  scenario.sensor_path = Resolve(map.Required<std::string>("sensor"), directory);
  scenario.camera_output =
      map.OptionalChoice("camera_output", CameraOutput::kDepthImage, kCameraOutputs);
  scenario.camera_binning = map.Optional<int>("camera_binning", 1);
  if (scenario.camera_binning < 1 || scenario.camera_binning > 16)
    map.Fail("camera_binning", "must be in 1..16");
  {
    StrictMap m = map.Map("sensor_mount");
    scenario.mount.x = m.RequiredFinite("x");
    scenario.mount.y = m.RequiredFinite("y");
    scenario.mount.z = m.RequiredFinite("z");
    scenario.mount.roll = m.RequiredFinite("roll");
    scenario.mount.pitch = m.RequiredFinite("pitch");
    scenario.mount.yaw = m.RequiredFinite("yaw");
    m.RejectUnknownKeys();
  }
  ReadScene(map.Map("scene"), scenario.scene, directory);
  ReadPlan(map.Map("plan"), scenario);
  if (scenario.scene.kind == SceneKind::kCell && !scenario.view_target_given &&
      scenario.plan.kind != PlanKind::kLidarSweeps) {
    map.Fail("plan", "needs view.target with a cell scene: the point the sensor must see");
  }
  scenario.plan.seed = scenario.seed;
  map.OptionalSection("truth", [&](StrictMap& m) {
    scenario.truth.target_position_rms =
        Positive(m, "position_rms", scenario.truth.target_position_rms);
    scenario.truth.angle_sigma = Positive(m, "angle_sigma", scenario.truth.angle_sigma);
    scenario.truth.translation_sigma =
        Positive(m, "translation_sigma", scenario.truth.translation_sigma);
    scenario.truth.samples = m.Optional<int>("samples", scenario.truth.samples);
    if (scenario.truth.samples < 10) m.Fail("samples", "must be at least 10");
    scenario.truth_joint_offsets = m.Optional<std::vector<double>>("joint_offsets", {});
    for (double offset : scenario.truth_joint_offsets) {
      if (!std::isfinite(offset)) m.Fail("joint_offsets", "must be finite");
    }
  });
  map.OptionalSection("joint_states", [&](StrictMap& m) {
    scenario.recording.joint_rate_hz = Positive(m, "rate_hz", scenario.recording.joint_rate_hz);
    if (scenario.recording.joint_rate_hz < 20 || scenario.recording.joint_rate_hz > 10000) {
      m.Fail("rate_hz", "must be in 20..10000 (the engine needs samples within 50 ms)");
    }
    scenario.recording.encoder_noise =
        NonNegative(m, "encoder_noise", scenario.recording.encoder_noise);
    scenario.recording.timestamp_jitter =
        NonNegative(m, "timestamp_jitter", scenario.recording.timestamp_jitter);
  });
  scenario.recording.latency = map.Optional<double>("sensor_latency", 0.0);
  if (!(std::abs(scenario.recording.latency) <= 0.04)) {
    map.Fail("sensor_latency",
             "must be within +-0.04 s (a frame must stay inside its scan's markers)");
  }
  map.OptionalSection("timing", [&](StrictMap& m) {
    scenario.recording.settle_time = Positive(m, "settle_time", scenario.recording.settle_time);
    // Sensor messages are logged up to 30 ms after END; the next segment starts a settle later.
    if (scenario.recording.settle_time < 0.05) m.Fail("settle_time", "must be at least 0.05 s");
    scenario.recording.transit_fraction =
        Positive(m, "transit_fraction", scenario.recording.transit_fraction);
    if (scenario.recording.transit_fraction > 1) m.Fail("transit_fraction", "must be at most 1");
    scenario.recording.stationary_hold =
        Positive(m, "stationary_hold", scenario.recording.stationary_hold);
  });
  if (map.Has("effects")) ReadEffects(map.Map("effects"), scenario.recording.effects);
  scenario.recording.seed = scenario.seed;
  return scenario;
}

std::string Pair(double a, double b) { return yaml::NumberList({a, b}); }
std::string Triple(const Eigen::Vector3d& v) { return yaml::NumberList({v.x(), v.y(), v.z()}); }
std::string Box(const Eigen::AlignedBox3d& box) {
  return "{min: " + Triple(box.min()) + ", max: " + Triple(box.max()) + "}";
}

void FormatScene(const sim::SceneSpec& scene, std::ostream& out) {
  out << "scene:\n";
  out << "  kind: " << kSceneKinds.Name(scene.kind) << "\n";
  if (scene.kind == SceneKind::kTabletop) {
    out << "  object: " << kSceneObjects.Name(scene.object) << "\n";
    if (scene.object == SceneObject::kBunny) out << "  mesh: " << Text(scene.bunny_path) << "\n";
    out << "  object_size: " << Number(scene.object_size) << "\n";
    out << "  object_position: " << Triple(scene.object_position) << "\n";
    out << "  object_yaw: " << Number(scene.object_yaw) << "\n";
  }
  if (scene.kind == SceneKind::kCell) {
    out << "  free_space: " << Box(scene.cell_free_space) << "\n";
    out << "  obstacles:" << (scene.cell_obstacles.empty() ? " []" : "") << "\n";
    for (const auto& box : scene.cell_obstacles) out << "    - " << Box(box) << "\n";
  }
  if (!scene.albedo.empty()) {
    out << "  albedo: {";
    for (std::size_t i = 0; i < scene.albedo.size(); ++i) {
      out << (i ? ", " : "") << scene.albedo[i].first << ": " << Number(scene.albedo[i].second);
    }
    out << "}\n";
  }
}

}  // namespace

Expected<Scenario> ParseScenario(const std::string& text, const std::string& name,
                                 const std::string& directory) {
  return yaml::ParseDocument<Scenario>(
      text, name, [&](StrictMap& map) { return ReadDocument(map, directory); });
}

Expected<Scenario> ReadScenarioFile(const std::string& path) {
  const std::string directory = std::filesystem::absolute(path).parent_path().string();
  return yaml::ReadDocumentFile<Scenario>(
      path, [&](StrictMap& map) { return ReadDocument(map, directory); });
}

std::string FormatScenario(const Scenario& s) {
  std::ostringstream out;
  out << "# Resolved by selfcal simulate: every key, absolute paths.\n";
  out << "name: " << Text(s.name) << "\n";
  out << "seed: " << s.seed << "\n";
  out << "start_utime: " << s.start_utime << "\n";
  out << "robot: " << Text(s.robot_path) << "\n";
  out << "sensor: " << Text(s.sensor_path) << "\n";
  out << "camera_output: " << kCameraOutputs.Name(s.camera_output) << "\n";
  out << "camera_binning: " << s.camera_binning << "\n";
  out << "sensor_mount: {x: " << Number(s.mount.x) << ", y: " << Number(s.mount.y)
      << ", z: " << Number(s.mount.z) << ", roll: " << Number(s.mount.roll)
      << ", pitch: " << Number(s.mount.pitch) << ", yaw: " << Number(s.mount.yaw) << "}\n";
  FormatScene(s.scene, out);
  const auto& plan = s.plan;
  out << "plan:\n";
  out << "  kind: " << kPlanKinds.Name(plan.kind) << "\n";
  out << "  scans: " << plan.fit_scans << "\n";
  out << "  validation_scans: " << plan.validation_scans << "\n";
  out << "  free_margin: " << Number(plan.free_margin) << "\n";
  out << "  limit_margin: " << Number(plan.limit_margin) << "\n";
  if (plan.link_radius > 0) out << "  link_radius: " << Number(plan.link_radius) << "\n";
  out << "  max_attempts: " << plan.max_attempts << "\n";
  if (plan.kind != PlanKind::kLidarSweeps) {
    const auto& v = plan.view;
    out << "  view:\n";
    out << "    target: " << Triple(v.target) << "\n";
    out << "    target_jitter: " << Number(v.target_jitter) << "\n";
    out << "    distance: " << Pair(v.distance_min, v.distance_max) << "\n";
    out << "    elevation: " << Pair(v.elevation_min, v.elevation_max) << "\n";
    out << "    azimuth: " << Pair(v.azimuth_min, v.azimuth_max) << "\n";
    out << "    roll: " << Pair(v.roll_min, v.roll_max) << "\n";
  }
  if (plan.kind == PlanKind::kLineSweeps) {
    out << "  sweep_length: " << Number(plan.sweep_length) << "\n";
    out << "  sweep_speed: " << Number(plan.sweep_speed) << "\n";
  }
  if (plan.kind == PlanKind::kLidarSweeps) {
    out << "  sweep_angle: " << Number(plan.sweep_angle) << "\n";
    out << "  line_spacing: " << Number(s.lidar_line_spacing) << "\n";
  }
  out << "truth:\n";
  out << "  position_rms: " << Number(s.truth.target_position_rms) << "\n";
  out << "  angle_sigma: " << Number(s.truth.angle_sigma) << "\n";
  out << "  translation_sigma: " << Number(s.truth.translation_sigma) << "\n";
  out << "  samples: " << s.truth.samples << "\n";
  if (!s.truth_joint_offsets.empty()) {
    out << "  joint_offsets: [";
    for (std::size_t j = 0; j < s.truth_joint_offsets.size(); ++j) {
      out << (j ? ", " : "") << Number(s.truth_joint_offsets[j]);
    }
    out << "]\n";
  }
  out << "joint_states:\n";
  out << "  rate_hz: " << Number(s.recording.joint_rate_hz) << "\n";
  out << "  encoder_noise: " << Number(s.recording.encoder_noise) << "\n";
  out << "  timestamp_jitter: " << Number(s.recording.timestamp_jitter) << "\n";
  out << "sensor_latency: " << Number(s.recording.latency) << "\n";
  out << "timing:\n";
  out << "  settle_time: " << Number(s.recording.settle_time) << "\n";
  out << "  transit_fraction: " << Number(s.recording.transit_fraction) << "\n";
  out << "  stationary_hold: " << Number(s.recording.stationary_hold) << "\n";
  out << FormatEffects(s.recording.effects);
  return out.str();
}

}  // namespace selfcal
