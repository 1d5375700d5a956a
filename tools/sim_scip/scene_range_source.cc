#include "tools/sim_scip/scene_range_source.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace selfcal::sim_scip {
namespace {

constexpr std::uint32_t kNoEchoCode = 1;  // UTM error codes are 0..DMIN-1: "no return"

std::uint32_t ToRangeCode(double range) {
  const double mm = std::round(range * 1000);
  // Outside DMIN..DMAX of the UTM-30LX the sensor reports an error code, not a range.
  return std::isfinite(mm) && mm >= 23 && mm <= 60000 ? static_cast<std::uint32_t>(mm)
                                                      : kNoEchoCode;
}

}  // namespace

Expected<std::unique_ptr<SceneRangeSource>> SceneRangeSource::Create(
    const std::string& scenario_path) {
  // The same true robot as `selfcal simulate` builds from the scenario (its seed and label).
  auto scenario = LoadDeviceScenario(scenario_path);
  if (!scenario) return scenario.error();
  std::unique_ptr<SceneRangeSource> source(new SceneRangeSource());
  source->scenario_ = std::move(*scenario);
  const RobotModel& truth = source->scenario_.setup.truth;
  source->joint_types_ = JointTypes(truth);
  source->parameters_ = ToParameterVector(truth);
  for (const auto& joint : truth.joints) source->joint_names_.push_back(joint.name);
  if (source->scenario_.frames->effects().walker.enabled) {
    auto seconds = DeviceScenarioScanSeconds(source->scenario_);
    if (!seconds) return seconds.error();
    source->scan_seconds_ = std::move(*seconds);
  }
  return source;
}

double SceneRangeSource::ClockDriftPpm() const {
  const sim::TimingEffect& timing = scenario_.frames->effects().timing;
  return scenario_.field && timing.enabled ? timing.clock_drift_ppm : 0;
}

void SceneRangeSource::AddScanMarker(double host_monotonic_us, int scan_index, bool begin) {
  if (!begin) return;  // the scan's things stay where they are until the next one begins
  std::lock_guard<std::mutex> lock(mutex_);
  scan_ = scan_index;
  scan_begin_us_ = host_monotonic_us;
  if (first_begin_us_ < 0) first_begin_us_ = host_monotonic_us;
}

double SceneRangeSource::WalkerFraction(double host_us) const {
  if (scan_ < 0 || scan_seconds_.empty()) return 0;
  // A scan beyond the scenario's plan (another plan's): the walk takes the plan's longest scan.
  const double seconds = scan_ < static_cast<int>(scan_seconds_.size())
                             ? scan_seconds_[static_cast<std::size_t>(scan_)]
                             : *std::max_element(scan_seconds_.begin(), scan_seconds_.end());
  return seconds > 0 ? std::clamp((host_us - scan_begin_us_) * 1e-6 / seconds, 0.0, 1.0) : 0.5;
}

double SceneRangeSource::Elapsed(double host_us) const {
  return first_begin_us_ < 0 ? 0 : std::max(0.0, (host_us - first_begin_us_) * 1e-6);
}

void SceneRangeSource::AddJointState(double host_monotonic_us, std::vector<double> positions) {
  if (positions.size() != joint_types_.size()) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (!samples_.empty() && host_monotonic_us <= samples_.back().host_us) return;
  // The play operator, sample by sample (the stream is linear in between, so monotonic); the
  // arm starts centred on the first.
  std::vector<double> output = positions;
  if (!samples_.empty()) Play(samples_.back().output, output);
  samples_.push_back({host_monotonic_us, std::move(positions), std::move(output)});
  while (samples_.front().host_us < host_monotonic_us - 10e6) samples_.pop_front();
}

bool SceneRangeSource::JointsAt(double host_us, std::vector<double>& joints) {
  if (samples_.empty()) return false;
  joints.resize(joint_types_.size());
  const Sample& newest = samples_.back();
  if (host_us <= samples_.front().host_us || samples_.size() < 2 ||
      (host_us >= newest.host_us && host_us - newest.host_us > 50e3)) {
    joints = host_us <= samples_.front().host_us ? samples_.front().output : newest.output;
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
  Play(a.output, joints);
  return true;
}

void SceneRangeSource::Play(const std::vector<double>& output, std::vector<double>& joints) const {
  const sim::BacklashEffect& backlash = scenario_.frames->effects().backlash;
  if (!scenario_.field || !backlash.enabled) return;
  for (std::size_t j = 0; j < joints.size(); ++j) {
    joints[j] = sim::PlayOutput(output[j], joints[j], backlash.angle);
  }
}

double SceneRangeSource::RangeAt(std::span<const double> joints, double angle) const {
  const Transform3<double> T_base_sensor =
      ForwardKinematics<double, double>(joint_types_, parameters_.data(), joints.data());
  const Eigen::Vector3d direction_sensor(std::cos(angle), std::sin(angle), 0.0);
  return scenario_.caster->Cast(T_base_sensor.translation(),
                                T_base_sensor.linear() * direction_sensor);
}

void SceneRangeSource::FieldRanges(const ScanTiming& timing, std::vector<double>& ranges) {
  const sim::DeviceFrameCaster& frames = *scenario_.frames;
  if (samples_.empty()) {  // no robot state yet
    ranges.assign(ranges.size(), std::numeric_limits<double>::quiet_NaN());
    return;
  }
  const int cluster = timing.cluster <= 1 ? 1 : timing.cluster;
  // A ray stamped s was measured at s + latency (simulator.h); joint states that lag the arm
  // report at t + joint_lag where it was at t.
  const sim::TimingEffect& lag = frames.effects().timing;
  const double shift_us =
      1e6 * (scenario_.setup.scenario.recording.latency + (lag.enabled ? lag.joint_lag : 0));
  auto ray_us = [&](std::size_t i) {
    return timing.host_time_us + shift_us +
           (timing.first_step + static_cast<int>(i) * cluster) * timing.host_us_per_step;
  };
  std::vector<Eigen::Vector3d> rays(ranges.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const int step = timing.first_step + static_cast<int>(i) * cluster;
    const double angle = 2 * std::numbers::pi * (step - timing.front_step) /
                         timing.steps_per_rotation / frames.FocalFactor();
    rays[i] = Eigen::Vector3d(std::cos(angle), std::sin(angle), 0);
  }
  // What moves once per request, at its middle ray; the sensor pose at every ray's time.
  const double middle_us = ray_us(ranges.size() / 2);
  JointsAt(middle_us, joints_);
  const sim::DynamicGeometry moving = frames.Moving(joints_, scan_, WalkerFraction(middle_us));
  const sim::CellReturns cells = frames.Cast(
      rays,
      [&](std::size_t i) {
        JointsAt(ray_us(i), joints_);
        return frames.SensorPose(joints_, Elapsed(ray_us(i)));
      },
      moving);
  // The device's own clock counts from power-on: the warm-up drift runs on it.
  ranges = frames.Measure(cells, static_cast<int>(ranges.size()), 1, timing.device_time_us * 1e-6,
                          timing.timestamp_ms);
}

void SceneRangeSource::Ranges(const ScanTiming& timing, std::span<std::uint32_t> ranges_mm,
                              std::span<std::uint32_t> intensities) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (scenario_.field) {
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
