// selfcal-sim-scene-lidar: a rotating LiDAR in a simulated scene, live over LCM. It follows the
// arm's true joint states (selfcal-sim-fri --truth-lcm-url) and publishes one
// selfcal.range_scan_t per rotation, each ray cast from the sensor pose of the TRUE model at the
// ray's own time (core/sim ray caster and sensor model, the code of `selfcal simulate`).
// It stands in for "SCIP simulator serving the scene + selfcal-hokuyo" in tools/demo until the
// SCIP simulator can serve a scene: it publishes what the Hokuyo driver would, without SCIP.
#include <spdlog/spdlog.h>

#include <cmath>
#include <deque>
#include <random>

#include "core/model/kinematics.h"
#include "core/sim/ray_caster.h"
#include "protocols/lcm/channels.h"
#include "protocols/program/program.h"
#include "protocols/scenario/scenario_file.h"
#include "protocols/scenario/simulation_setup.h"
#include "selfcal/joint_state_t.hpp"
#include "selfcal/range_scan_t.hpp"

namespace {

namespace program = selfcal::program;

constexpr program::About kAbout{
    "selfcal-sim-scene-lidar",
    "selfcal-sim-scene-lidar: a rotating LiDAR in a simulated scene, live over LCM, "
    "following the true joint states of selfcal-sim-fri"};

struct Settings {
  std::string scenario_path;
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  std::string truth_channel = selfcal::channels::kSimJointTruth;
  std::string channel = selfcal::channels::kRangeScan;
  std::uint64_t seed = 7;
};

void DescribeOptions(program::Program& p, Settings& s) {
  p.Option("--scenario", s.scenario_path, "Scenario file (scene, sensor, seeded truth)")
      ->required();
  p.LcmUrlOption(s.lcm_url);
  p.Option("--truth-channel", s.truth_channel, "True joint states (selfcal.joint_state_t)");
  p.Option("--channel", s.channel, "Where the scans go (selfcal.range_scan_t)");
  p.Option("--seed", s.seed, "Noise seed");
}

struct Sample {
  std::int64_t utime;
  std::vector<double> q;
};

// Linear interpolation of the true joint positions at `utime`; false when not bracketed
// within 50 ms (docs/recording.md's rule).
bool Interpolate(const std::deque<Sample>& samples, std::int64_t utime, std::vector<double>& q) {
  for (std::size_t i = 1; i < samples.size(); ++i) {
    if (samples[i].utime < utime) continue;
    const Sample& a = samples[i - 1];
    const Sample& b = samples[i];
    if (a.utime > utime || b.utime - a.utime > 50'000) return false;
    const double s = b.utime == a.utime ? 0.0
                                        : static_cast<double>(utime - a.utime) /
                                              static_cast<double>(b.utime - a.utime);
    q.resize(a.q.size());
    for (std::size_t j = 0; j < q.size(); ++j) q[j] = a.q[j] + s * (b.q[j] - a.q[j]);
    return true;
  }
  return false;
}

// Casts rotations of the scenario's LiDAR from the true arm, one rotation at a time.
class RotationCaster {
 public:
  RotationCaster(const selfcal::SimulationSetup& setup, const selfcal::sim::RayCaster& caster,
                 std::uint64_t seed)
      : sensor_(setup.sensor), truth_(setup.truth), caster_(caster), random_(seed) {
    rays_ = sensor_.Rays();
    for (auto& ray : rays_) ray.normalize();
    period_us_ = static_cast<std::int64_t>(std::llround(sensor_.rotation_period * 1e6));
    span_us_ = static_cast<std::int64_t>(
        std::ceil((static_cast<double>(rays_.size()) - 1) * sensor_.time_per_ray * 1e6));
    scan_.device_utime = -1;
    scan_.time_per_ray = sensor_.time_per_ray;
    scan_.angle_first = sensor_.angle_first;
    scan_.angle_increment = sensor_.angle_increment;
    scan_.num_ranges = static_cast<std::int32_t>(rays_.size());
    scan_.num_intensities = 0;
  }
  std::size_t ray_count() const { return rays_.size(); }
  std::int64_t period_us() const { return period_us_; }
  std::int64_t span_us() const { return span_us_; }

  // The rotation starting at `start_utime`; false when joint states are missing for a ray.
  bool Cast(const std::deque<Sample>& samples, std::int64_t start_utime, std::int64_t counter) {
    scan_.utime = start_utime;
    scan_.scan_counter = counter;
    scan_.ranges.assign(rays_.size(), std::nanf(""));
    for (std::size_t i = 0; i < rays_.size(); ++i) {
      const auto t = start_utime + static_cast<std::int64_t>(std::llround(
                                       static_cast<double>(i) * sensor_.time_per_ray * 1e6));
      if (!Interpolate(samples, t, q_)) return false;
      const auto T_base_sensor = selfcal::ForwardKinematics(truth_, q_);
      const double range = caster_.Cast(T_base_sensor.translation(),
                                        T_base_sensor.linear() * rays_[i], sensor_.range_max * 1.1);
      if (!std::isfinite(range)) continue;
      const double noisy = range + sensor_.Sigma(range) * gaussian_(random_);
      if (noisy >= sensor_.range_min && noisy <= sensor_.range_max) {
        scan_.ranges[i] = static_cast<float>(noisy);
      }
    }
    return true;
  }
  const selfcal::range_scan_t& scan() const { return scan_; }

 private:
  const selfcal::sim::SensorModel& sensor_;
  const selfcal::RobotModel& truth_;
  const selfcal::sim::RayCaster& caster_;
  std::mt19937_64 random_;
  std::normal_distribution<double> gaussian_{0.0, 1.0};
  std::vector<Eigen::Vector3d> rays_;
  std::int64_t period_us_ = 0, span_us_ = 0;
  selfcal::range_scan_t scan_;
  std::vector<double> q_;
};

int Run(selfcal::Bus& bus, const Settings& s, const selfcal::RobotModel& truth,
        RotationCaster& rotations) {
  std::deque<Sample> samples;
  bus.Subscribe(s.truth_channel, [&](const selfcal::BusMessage& message) {
    auto state = selfcal::DecodeLcm<selfcal::joint_state_t>(message.data, message.channel);
    if (!state || state->positions.size() != truth.JointCount()) return;
    if (!samples.empty() && state->utime <= samples.back().utime) return;
    samples.push_back({state->utime, state->positions});
    while (samples.size() > 4000) samples.pop_front();
  });
  const std::atomic<bool>& stop = program::StopOnSignals();
  std::int64_t next_start = 0, counter = 0, published = 0, skipped = 0;
  while (!stop.load()) {
    auto handled = bus.HandleOnce(std::chrono::milliseconds(5));
    if (!handled && stop.load()) break;  // a signal interrupted the receive
    if (!handled) return program::Fail(handled.error().message);
    if (samples.size() < 2) continue;
    if (next_start == 0) next_start = samples.back().utime;
    // A rotation is cast once the true joint states cover all of it.
    while (samples.back().utime >= next_start + rotations.span_us()) {
      if (rotations.Cast(samples, next_start, counter++)) {
        (void)bus.Publish(s.channel, rotations.scan());
        ++published;
      } else {
        ++skipped;
      }
      next_start += rotations.period_us();
      // Fell behind (a pause in the truth stream): restart at the newest sample.
      if (samples.back().utime - next_start > 10 * rotations.period_us()) {
        next_start = samples.back().utime;
      }
    }
  }
  spdlog::info("stopping: {} rotations published, {} skipped (joint states missing)", published,
               skipped);
  return program::kExitOk;
}

// Everything after the command line: read files, open the bus, echo, run.
int Start(program::Program& program, Settings& s) {
  auto scenario = selfcal::ReadScenarioFile(s.scenario_path);
  if (!scenario) return program::Fail(scenario.error().message);
  auto setup = selfcal::PrepareSimulation(std::move(scenario).value());
  if (!setup) return program::Fail(setup.error().message);
  if (setup->sensor.kind != selfcal::SensorLayout::kRotatingLidar) {
    return program::Fail(s.scenario_path + ": the scenario's sensor is not a rotating LiDAR");
  }
  auto caster = selfcal::sim::RayCaster::Create(setup->scene);
  if (!caster) return program::Fail(caster.error().message);
  auto bus = program.OpenBus(s.lcm_url);
  if (!bus) return program::Fail(bus.error().message);
  RotationCaster rotations(*setup, **caster, s.seed);
  program.EchoValue("scene", [&] { return setup->scene.name; });
  program.EchoValue("triangles",
                    [&] { return std::to_string(setup->scene.mesh.triangles.size()); });
  program.EchoValue("rays", [&] { return std::to_string(rotations.ray_count()); });
  program.EchoValue("rotation_period_s",
                    [&] { return program::FormatValue(setup->sensor.rotation_period); });
  program.EchoValue("time_per_ray_s",
                    [&] { return program::FormatValue(setup->sensor.time_per_ray); });
  program.LogConfiguration();
  return Run(**bus, s, setup->truth, rotations);
}

}  // namespace

int main(int argc, char** argv) {
  return program::Main<Settings>(argc, argv, kAbout, DescribeOptions, Start);
}
