#include "tools/sim_scip/scene_range_source.h"

#include <cmath>
#include <numbers>

#include "core/sim/ground_truth.h"
#include "core/sim/mount.h"
#include "core/sim/random.h"
#include "protocols/model_file/model_file.h"
#include "protocols/model_file/sensor_config.h"
#include "protocols/scenario/scenario_file.h"

namespace selfcal::sim_scip {
namespace {

// The label `selfcal simulate` derives the truth's seed with (tools/selfcal/cmd_simulate.cc):
// the same scenario gives the same true robot here and there.
constexpr std::uint64_t kTruthLabel = 0x7247;
constexpr std::uint32_t kNoEchoCode = 1;  // UTM error codes are 0..DMIN-1: "no return"
constexpr std::uint64_t kNoiseLabel = 0x5c1b0;
constexpr std::uint64_t kMixLabel = 0x5c1b1;

std::uint32_t ToRangeCode(double range) {
  const double mm = std::round(range * 1000);
  // Outside DMIN..DMAX of the UTM-30LX the sensor reports an error code, not a range.
  return std::isfinite(mm) && mm >= 23 && mm <= 60000 ? static_cast<std::uint32_t>(mm)
                                                      : kNoEchoCode;
}

}  // namespace

Expected<std::unique_ptr<SceneRangeSource>> SceneRangeSource::Create(
    const std::string& scenario_path) {
  auto scenario = ReadScenarioFile(scenario_path);
  if (!scenario) return scenario.error();
  auto robot = ReadModelFile(scenario->robot_path);
  if (!robot) return robot.error();
  auto scene = sim::BuildScene(scenario->scene);
  if (!scene) return Error{scenario_path + ": " + scene.error().message};
  auto caster = sim::RayCaster::Create(*scene);
  if (!caster) return Error{scenario_path + ": " + caster.error().message};
  std::unique_ptr<SceneRangeSource> source(new SceneRangeSource());
  source->scene_ = std::move(*scene);
  source->caster_ = std::move(*caster);
  const RobotModel nominal = sim::WithSensorMount(robot->model, scenario->mount);
  source->truth_ =
      sim::PerturbModel(nominal, sim::SubKey(scenario->seed, kTruthLabel), scenario->truth);
  source->joint_types_ = JointTypes(source->truth_);
  source->parameters_ = ToParameterVector(source->truth_);
  for (const auto& joint : source->truth_.joints) source->joint_names_.push_back(joint.name);
  source->effects_ = scenario->recording.effects;
  source->field_ = scenario->recording.effects.AnyEnabled();
  source->seed_ = scenario->seed;
  if (source->field_) {
    auto sensor = ReadSensorConfig(scenario->sensor_path);
    if (!sensor) return sensor.error();
    source->sigma_abs_ = sensor->sigma_abs;
    source->sigma_rel_ = sensor->sigma_rel;
  }
  return source;
}

void SceneRangeSource::AddJointState(double host_monotonic_us, std::vector<double> positions) {
  if (positions.size() != joint_types_.size()) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (!samples_.empty() && host_monotonic_us <= samples_.back().host_us) return;
  samples_.push_back({host_monotonic_us, std::move(positions)});
  while (samples_.front().host_us < host_monotonic_us - 10e6) samples_.pop_front();
}

bool SceneRangeSource::JointsAt(double host_us, std::vector<double>& joints) {
  if (samples_.empty()) return false;
  joints.resize(joint_types_.size());
  const Sample& newest = samples_.back();
  if (host_us <= samples_.front().host_us || samples_.size() < 2 ||
      (host_us >= newest.host_us && host_us - newest.host_us > 50e3)) {
    joints = host_us <= samples_.front().host_us ? samples_.front().positions : newest.positions;
    return true;
  }
  // Between two states: linear interpolation, as the paper does. Past the newest (the truth
  // arrives in batches): the arm keeps its velocity that long, so the last two are extrapolated;
  // beyond 50 ms it holds still (above).
  std::size_t lo = samples_.size() - 2;
  std::size_t hi = samples_.size() - 1;
  if (host_us < newest.host_us) {
    lo = 0;
    while (hi - lo > 1) {  // binary search for the bracketing pair
      const std::size_t mid = (lo + hi) / 2;
      (samples_[mid].host_us <= host_us ? lo : hi) = mid;
    }
  }
  const Sample& a = samples_[lo];
  const Sample& b = samples_[hi];
  const double w = (host_us - a.host_us) / (b.host_us - a.host_us);
  for (std::size_t j = 0; j < joints.size(); ++j) {
    joints[j] = a.positions[j] + w * (b.positions[j] - a.positions[j]);
  }
  return true;
}

double SceneRangeSource::RangeAt(std::span<const double> joints, double angle) const {
  const Transform3<double> T_base_sensor =
      ForwardKinematics<double, double>(joint_types_, parameters_.data(), joints.data());
  const Eigen::Vector3d direction_sensor(std::cos(angle), std::sin(angle), 0.0);
  return caster_->Cast(T_base_sensor.translation(), T_base_sensor.linear() * direction_sensor);
}

void SceneRangeSource::FieldRanges(const ScanTiming& timing, std::vector<double>& ranges) {
  const int cluster = timing.cluster <= 1 ? 1 : timing.cluster;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> cosines(ranges.size(), 1.0);
  auto ray_us = [&](std::size_t i) {
    return timing.host_time_us +
           (timing.first_step + static_cast<int>(i) * cluster) * timing.host_us_per_step;
  };
  // The arm's links once per request, at its middle ray.
  sim::DynamicGeometry geometry;
  if (effects_.self_view.enabled && JointsAt(ray_us(ranges.size() / 2), joints_)) {
    sim::DeflectJoints(effects_.joint_elasticity, joint_types_, parameters_.data(), joints_.data());
    geometry.capsules =
        sim::ArmCapsules(sim::ComputeArmFrames(joint_types_, parameters_.data(), joints_.data()),
                         effects_.self_view.radius);
  }
  const double focal = effects_.intrinsics.enabled ? 1 + effects_.intrinsics.focal_scale : 1.0;
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    ranges[i] = nan;
    if (!JointsAt(ray_us(i), joints_)) continue;
    sim::DeflectJoints(effects_.joint_elasticity, joint_types_, parameters_.data(), joints_.data());
    const Transform3<double> T =
        ForwardKinematics<double, double>(joint_types_, parameters_.data(), joints_.data());
    const int step = timing.first_step + static_cast<int>(i) * cluster;
    const double angle =
        2 * std::numbers::pi * (step - timing.front_step) / timing.steps_per_rotation / focal;
    const Eigen::Vector3d direction =
        T.linear() * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0);
    const sim::RayReturn hit =
        sim::CastFieldRay(*caster_, geometry, effects_, T.translation(), direction, 60.0);
    if (!std::isfinite(hit.distance)) continue;
    // The device's own clock counts from power-on: the warm-up drift runs on it.
    ranges[i] =
        sim::SystematicMeasure(effects_, hit.distance, hit.cosine, timing.device_time_us * 1e-6);
    cosines[i] = hit.cosine;
  }
  const sim::CounterRandom mix(sim::SubKey(seed_, kMixLabel, timing.timestamp_ms));
  ranges = sim::MixPixels(effects_.mixed_pixels, ranges, static_cast<int>(ranges.size()), 1,
                          [&](std::size_t i, int draw) {
                            return mix.Uniform(2 * i + static_cast<std::uint64_t>(draw));
                          });
  const sim::CounterRandom noise(sim::SubKey(seed_, kNoiseLabel, timing.timestamp_ms));
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    if (!std::isfinite(ranges[i])) continue;
    const double sigma = (sigma_abs_ + sigma_rel_ * ranges[i]) *
                         sim::IncidenceNoiseFactor(effects_.incidence_noise, cosines[i]);
    ranges[i] += sigma * noise.Gaussian(i);
  }
}

void SceneRangeSource::Ranges(const ScanTiming& timing, std::span<std::uint32_t> ranges_mm,
                              std::span<std::uint32_t> intensities) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (field_) {
    std::vector<double> ranges(ranges_mm.size());
    FieldRanges(timing, ranges);
    for (std::size_t i = 0; i < ranges_mm.size(); ++i) {
      ranges_mm[i] = ToRangeCode(ranges[i]);
      if (i < intensities.size()) intensities[i] = ranges_mm[i] > kNoEchoCode ? 2000u : 0u;
    }
    return;
  }
  const int cluster = timing.cluster <= 1 ? 1 : timing.cluster;
  for (std::size_t i = 0; i < ranges_mm.size(); ++i) {
    const int step = timing.first_step + static_cast<int>(i) * cluster;
    const double ray_us = timing.host_time_us + step * timing.host_us_per_step;
    if (!JointsAt(ray_us, joints_)) {
      ranges_mm[i] = kNoEchoCode;  // no robot state yet
      continue;
    }
    const double angle =
        2 * std::numbers::pi * (step - timing.front_step) / timing.steps_per_rotation;
    ranges_mm[i] = ToRangeCode(RangeAt(joints_, angle));
    if (i < intensities.size()) intensities[i] = ranges_mm[i] > kNoEchoCode ? 2000u : 0u;
  }
}

}  // namespace selfcal::sim_scip
