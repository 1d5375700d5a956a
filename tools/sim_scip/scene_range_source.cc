#include "tools/sim_scip/scene_range_source.h"

#include <cmath>
#include <numbers>

#include "core/sim/ground_truth.h"
#include "core/sim/mount.h"
#include "core/sim/random.h"
#include "protocols/model_file/model_file.h"
#include "protocols/scenario/scenario_file.h"

namespace selfcal::sim_scip {
namespace {

// The label `selfcal simulate` derives the truth's seed with (tools/selfcal/cmd_simulate.cc):
// the same scenario gives the same true robot here and there.
constexpr std::uint64_t kTruthLabel = 0x7247;
constexpr std::uint32_t kNoEchoCode = 1;  // UTM error codes are 0..DMIN-1: "no return"

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

void SceneRangeSource::Ranges(const ScanTiming& timing, std::span<std::uint32_t> ranges_mm,
                              std::span<std::uint32_t> intensities) {
  std::lock_guard<std::mutex> lock(mutex_);
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
    const double range = RangeAt(joints_, angle);
    const double mm = std::round(range * 1000);
    // Outside DMIN..DMAX of the UTM-30LX the sensor reports an error code, not a range.
    ranges_mm[i] =
        std::isfinite(mm) && mm >= 23 && mm <= 60000 ? static_cast<std::uint32_t>(mm) : kNoEchoCode;
    if (i < intensities.size()) intensities[i] = ranges_mm[i] > kNoEchoCode ? 2000u : 0u;
  }
}

}  // namespace selfcal::sim_scip
