#include "tools/sim_wenglor/scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/sim/ray_caster.h"
#include "core/sim/scene.h"
#include "protocols/scenario/device_scenario.h"

namespace selfcal::sim_wenglor {
namespace {

// splitmix64: a small, fast, reproducible generator (no global state, one stream per profile).
std::uint64_t SplitMix(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

double Uniform(std::uint64_t& state) {
  return (static_cast<double>(SplitMix(state) >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

// Box-Muller: one standard normal sample.
double Normal(std::uint64_t& state) {
  const double u1 = Uniform(state);
  const double u2 = Uniform(state);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

}  // namespace

bool IsAnalyticScene(const std::string& name) {
  return name == "plane" || name == "box" || name == "sphere" || name == "objects";
}

bool IsKnownScene(const std::string& name) { return IsAnalyticScene(name) || name == "bunny"; }

LineScannerScene::LineScannerScene(SceneConfig config) : config_(std::move(config)) {
  has_box_ = config_.scene == "box" || config_.scene == "objects";
  has_sphere_ = config_.scene == "sphere" || config_.scene == "objects";
}

LineScannerScene::~LineScannerScene() = default;

Expected<bool> LineScannerScene::LoadScenario() {
  auto loaded = LoadDeviceScenario(config_.scenario);
  if (!loaded) return loaded.error();
  if (loaded->setup.sensor.kind != SensorLayout::kLineScanner) {
    return Error{config_.scenario + ": key 'sensor' must name a line scanner"};
  }
  auto scan = DeviceScenarioScan(*loaded, config_.view);
  if (!scan) return Error{config_.scenario + ": " + scan.error().message};
  sweep_start_ = scan->start;
  sweep_end_ = scan->end;
  pass_time_ = scan->peak_rate > 0 ? 1 / scan->peak_rate : 1.0;
  // The columns, fan and working range the fake reports (its info XML) are the ones it casts.
  sim::SensorModel sensor = loaded->setup.sensor;
  sensor.width = config_.columns;
  sensor.fan_angle = config_.fan_angle;
  sensor.range_min = config_.z_start;
  sensor.range_max = config_.z_start + config_.z_range;
  loaded->frames = std::make_unique<sim::DeviceFrameCaster>(
      *loaded->caster, loaded->setup.truth, sensor, loaded->setup.scenario.recording.effects,
      loaded->setup.scenario.seed);
  scenario_ = std::make_unique<DeviceScenario>(std::move(*loaded));
  return true;
}

double LineScannerScene::SweepFraction(double t) const {
  // Triangle wave: start to end in pass_time_, then back.
  const double phase = std::fmod(std::max(t, 0.0) / pass_time_, 2.0);
  return phase <= 1 ? phase : 2 - phase;
}

std::vector<double> LineScannerScene::JointsAt(double t) const {
  if (!scenario_) return {};
  const double f = SweepFraction(t);
  std::vector<double> q(sweep_start_.size());
  for (std::size_t j = 0; j < q.size(); ++j) {
    q[j] = sweep_start_[j] + f * (sweep_end_[j] - sweep_start_[j]);
  }
  return q;
}

double LineScannerScene::MeasuredAt(double t) const {
  return scenario_ && scenario_->field ? t + scenario_->setup.scenario.recording.latency : t;
}

std::vector<double> LineScannerScene::ArmJointsAt(double t) const {
  if (!scenario_ || !scenario_->field) return JointsAt(t);
  const double measured = MeasuredAt(t);
  std::vector<double> q = JointsAt(measured);
  const sim::BacklashEffect& backlash = scenario_->frames->effects().backlash;
  if (!backlash.enabled) return q;
  // Pass n runs start to end for even n, back for odd n; every joint moves monotonically within
  // a pass. The arm starts centred on the start; where it is when a pass begins repeats from the
  // third pass on.
  const auto pass = static_cast<long>(std::max(measured, 0.0) / pass_time_);
  const long passes_before = pass < 4 ? pass : 2 + pass % 2;
  for (std::size_t j = 0; j < q.size(); ++j) {
    double arm = sweep_start_[j];
    for (long k = 0; k < passes_before; ++k) {
      arm = sim::PlayOutput(arm, k % 2 == 0 ? sweep_end_[j] : sweep_start_[j], backlash.angle);
    }
    q[j] = sim::PlayOutput(arm, q[j], backlash.angle);
  }
  return q;
}

Expected<std::unique_ptr<LineScannerScene>> LineScannerScene::Create(SceneConfig config) {
  if (!config.scenario.empty()) {
    auto scene = std::make_unique<LineScannerScene>(config);
    if (auto loaded = scene->LoadScenario(); !loaded) return loaded.error();
    return scene;
  }
  if (!IsKnownScene(config.scene)) return Error{"unknown scene '" + config.scene + "'"};
  auto scene = std::make_unique<LineScannerScene>(config);
  if (config.scene == "bunny") {
    sim::SceneSpec spec;
    spec.kind = sim::SceneSpec::Kind::kTabletop;
    spec.object = sim::SceneSpec::Object::kBunny;
    spec.bunny_path = config.bunny_path;
    spec.object_size = 0.16;
    spec.object_position = Eigen::Vector3d::Zero();
    auto built = sim::BuildScene(spec);
    if (!built.ok()) return built.error();
    auto caster = sim::RayCaster::Create(*built);
    if (!caster.ok()) return caster.error();
    scene->mesh_caster_ = std::move(*caster);
  }
  return scene;
}

Eigen::Isometry3d LineScannerScene::PoseAt(double t) const {
  if (scenario_) return scenario_->frames->SensorPose(ArmJointsAt(t), MeasuredAt(t));
  // Triangle wave: out along +y, back along -y, period 2 * sweep / speed.
  const double length = config_.sweep_length;
  double y = 0;
  if (length > 0 && config_.speed > 0) {
    const double travelled = std::fmod(config_.speed * t + 0.5 * length, 2.0 * length);
    y = (travelled <= length ? travelled : 2.0 * length - travelled) - 0.5 * length;
  }
  Eigen::Isometry3d T_world_sensor = Eigen::Isometry3d::Identity();
  Eigen::Matrix3d R_world_sensor;
  R_world_sensor.col(0) = Eigen::Vector3d::UnitX();   // x_sensor = x_world
  R_world_sensor.col(1) = -Eigen::Vector3d::UnitY();  // y_sensor = z_sensor x x_sensor
  R_world_sensor.col(2) = -Eigen::Vector3d::UnitZ();  // z_sensor looks down
  T_world_sensor.linear() = R_world_sensor;
  T_world_sensor.translation() = Eigen::Vector3d(0, y, config_.height);
  return T_world_sensor;
}

Eigen::Vector3d LineScannerScene::RayDirection(int column) const {
  if (scenario_) return scenario_->frames->rays()[static_cast<std::size_t>(column)].normalized();
  const int n = config_.columns;
  const double angle =
      n > 1 ? -0.5 * config_.fan_angle + config_.fan_angle * column / (n - 1) : 0.0;
  return {std::sin(angle), 0.0, std::cos(angle)};
}

bool LineScannerScene::Cast(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double& range,
                            double& cos_incidence) const {
  double best = std::numeric_limits<double>::infinity();
  if (scenario_) {
    const sim::RayCaster::Hit hit = scenario_->caster->CastHit(o, d, 10.0);
    if (!std::isfinite(hit.distance)) return false;
    range = hit.distance;
    cos_incidence = std::abs(hit.normal.dot(d));
    return true;
  }
  if (mesh_caster_) {
    // core/sim gives the distance, not the surface normal: intensities of the bunny scene are
    // those of a surface facing the sensor.
    best = mesh_caster_->Cast(o, d, 10.0);
    if (!std::isfinite(best)) return false;
    range = best;
    cos_incidence = 1.0;
    return true;
  }
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  if (d.z() < 0) {  // ground plane z = 0
    const double t = -o.z() / d.z();
    if (t > 0 && t < best) {
      best = t;
      normal = Eigen::Vector3d::UnitZ();
    }
  }
  if (has_box_) {  // slab method
    double t_near = -std::numeric_limits<double>::infinity();
    double t_far = std::numeric_limits<double>::infinity();
    int near_axis = -1;
    bool miss = false;
    for (int axis = 0; axis < 3 && !miss; ++axis) {
      if (std::abs(d[axis]) < 1e-15) {
        if (o[axis] < box_min_[axis] || o[axis] > box_max_[axis]) miss = true;
        continue;
      }
      double t1 = (box_min_[axis] - o[axis]) / d[axis];
      double t2 = (box_max_[axis] - o[axis]) / d[axis];
      if (t1 > t2) std::swap(t1, t2);
      if (t1 > t_near) {
        t_near = t1;
        near_axis = axis;
      }
      t_far = std::min(t_far, t2);
    }
    if (!miss && near_axis >= 0 && t_near <= t_far && t_near > 0 && t_near < best) {
      best = t_near;
      normal = Eigen::Vector3d::Zero();
      normal[near_axis] = d[near_axis] > 0 ? -1.0 : 1.0;
    }
  }
  if (has_sphere_) {
    const Eigen::Vector3d oc = o - sphere_center_;
    const double b = oc.dot(d);
    const double c = oc.squaredNorm() - sphere_radius_ * sphere_radius_;
    const double discriminant = b * b - c;
    if (discriminant >= 0) {
      const double t = -b - std::sqrt(discriminant);
      if (t > 0 && t < best) {
        best = t;
        normal = (o + t * d - sphere_center_).normalized();
      }
    }
  }
  if (!std::isfinite(best)) return false;
  range = best;
  cos_incidence = std::abs(normal.dot(d));
  return true;
}

void LineScannerScene::Fill(double t, const std::uint64_t* noise_index,
                            std::vector<Column>& columns) const {
  columns.resize(static_cast<std::size_t>(config_.columns));
  const Eigen::Isometry3d T_world_sensor = PoseAt(t);
  std::uint64_t state = noise_index != nullptr ? config_.seed * 0x100000001B3ULL ^
                                                     (*noise_index * 0x9E3779B97F4A7C15ULL)
                                               : 0;
  for (int i = 0; i < config_.columns; ++i) {
    Column& column = columns[static_cast<std::size_t>(i)];
    column = Column{};
    const Eigen::Vector3d d_sensor = RayDirection(i);
    const Eigen::Vector3d d_world = T_world_sensor.linear() * d_sensor;
    double range = 0;
    double cos_incidence = 0;
    // Draw the noise for every column, hit or not, so that column i always uses the same samples.
    const double noise = noise_index != nullptr ? config_.noise_sigma * Normal(state) : 0.0;
    if (!Cast(T_world_sensor.translation(), d_world, range, cos_incidence)) continue;
    range += noise;
    const double x = range * d_sensor.x();
    const double z = range * d_sensor.z();
    if (z < config_.z_start || z > config_.z_start + config_.z_range) continue;
    column.hit = true;
    column.x = x;
    column.z = z;
    column.intensity =
        std::clamp(static_cast<int>(std::lround(100 + 900 * cos_incidence)), 0, 1023);
    column.peak_width =
        std::clamp(static_cast<int>(std::lround(3 + 10 * (1 - cos_incidence))), 0, 31);
  }
}

void LineScannerScene::FillField(double t, std::uint64_t index,
                                 std::vector<Column>& columns) const {
  const sim::DeviceFrameCaster& frames = *scenario_->frames;
  // The walker walks as far as the sweep has come (back again on the way back).
  const sim::CellReturns cells =
      frames.Cast(frames.true_rays(), config_.columns, PoseAt(t),
                  frames.Moving(ArmJointsAt(t), config_.view, SweepFraction(MeasuredAt(t))));
  // The device's clock runs from the start of the acquisition: the warm-up drift runs on it.
  const std::vector<double> measures = frames.Measure(cells, config_.columns, 1, t, index);
  columns.assign(static_cast<std::size_t>(config_.columns), Column{});
  for (std::size_t i = 0; i < columns.size(); ++i) {
    if (!std::isfinite(measures[i])) continue;
    Column& column = columns[i];
    const double cos_incidence = cells.cosines[i];
    column.hit = true;
    column.z = measures[i];  // along z: the sensor file's rays are scaled to z = 1
    column.x = measures[i] * frames.rays()[i].x();
    column.intensity =
        std::clamp(static_cast<int>(std::lround(100 + 900 * cos_incidence)), 0, 1023);
    column.peak_width =
        std::clamp(static_cast<int>(std::lround(3 + 10 * (1 - cos_incidence))), 0, 31);
  }
}

void LineScannerScene::Trace(double t, std::vector<Column>& columns) const {
  Fill(t, nullptr, columns);
}

void LineScannerScene::Measure(double t, std::uint64_t index, std::vector<Column>& columns) const {
  if (scenario_ && scenario_->field) {
    FillField(t, index, columns);
    return;
  }
  Fill(t, &index, columns);
}

}  // namespace selfcal::sim_wenglor
