#include "tools/sim_wenglor/scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/sim/ray_caster.h"
#include "core/sim/scene.h"

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

Expected<std::unique_ptr<LineScannerScene>> LineScannerScene::Create(SceneConfig config) {
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
  const int n = config_.columns;
  const double angle =
      n > 1 ? -0.5 * config_.fan_angle + config_.fan_angle * column / (n - 1) : 0.0;
  return {std::sin(angle), 0.0, std::cos(angle)};
}

bool LineScannerScene::Cast(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double& range,
                            double& cos_incidence) const {
  double best = std::numeric_limits<double>::infinity();
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

void LineScannerScene::Trace(double t, std::vector<Column>& columns) const {
  Fill(t, nullptr, columns);
}

void LineScannerScene::Measure(double t, std::uint64_t index, std::vector<Column>& columns) const {
  Fill(t, &index, columns);
}

}  // namespace selfcal::sim_wenglor
