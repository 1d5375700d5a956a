// selfcal-sim-scene-lidar: a rotating LiDAR in a simulated scene, live over LCM. It follows the
// arm's true joint states (selfcal-sim-fri --truth-lcm-url) and publishes one
// selfcal.range_scan_t per rotation, each ray cast from the sensor pose of the TRUE model at the
// ray's own time (core/sim ray caster and sensor model, the code of `selfcal simulate`).
// It stands in for "SCIP simulator serving the scene + selfcal-hokuyo" in tools/demo until the
// SCIP simulator can serve a scene: it publishes what the Hokuyo driver would, without SCIP.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <csignal>
#include <deque>
#include <iostream>
#include <random>

#include "core/model/kinematics.h"
#include "core/sim/ray_caster.h"
#include "protocols/bus/bus.h"
#include "protocols/scenario/scenario_file.h"
#include "protocols/scenario/simulation_setup.h"
#include "selfcal/joint_state_t.hpp"
#include "selfcal/range_scan_t.hpp"

namespace {

volatile std::sig_atomic_t g_stop = 0;
void OnSignal(int) { g_stop = 1; }

int Fail(const std::string& reason) {
  std::cerr << "error: " << reason << "\n";
  return 1;
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

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "selfcal-sim-scene-lidar: a rotating LiDAR in a simulated scene, live over LCM, "
      "following the true joint states of selfcal-sim-fri"};
  std::string scenario_path;
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  std::string truth_channel = "SELFCAL_SIM_JOINT_TRUTH";
  std::string channel = "SELFCAL_RANGE_SCAN";
  std::uint64_t seed = 7;
  app.add_option("--scenario", scenario_path, "Scenario file (scene, sensor, seeded truth)")
      ->required();
  app.add_option("--lcm-url", lcm_url, "LCM URL");
  app.add_option("--truth-channel", truth_channel, "True joint states (selfcal.joint_state_t)");
  app.add_option("--channel", channel, "Where the scans go (selfcal.range_scan_t)");
  app.add_option("--seed", seed, "Noise seed");
  CLI11_PARSE(app, argc, argv);
  spdlog::set_default_logger(spdlog::stderr_color_mt("selfcal-sim-scene-lidar"));

  auto scenario = selfcal::ReadScenarioFile(scenario_path);
  if (!scenario) return Fail(scenario.error().message);
  auto setup = selfcal::PrepareSimulation(std::move(scenario).value());
  if (!setup) return Fail(setup.error().message);
  if (setup->sensor.kind != selfcal::sim::SensorKind::kRotatingLidar) {
    return Fail(scenario_path + ": the scenario's sensor is not a rotating LiDAR");
  }
  auto caster = selfcal::sim::RayCaster::Create(setup->scene);
  if (!caster) return Fail(caster.error().message);
  auto bus = selfcal::OpenLcmBus(lcm_url);
  if (!bus) return Fail(bus.error().message);
  const auto& sensor = setup->sensor;
  const auto& truth = setup->truth;
  std::vector<Eigen::Vector3d> rays = sensor.Rays();
  for (auto& ray : rays) ray.normalize();
  spdlog::info(
      "scenario={} seed={} scene={} ({} triangles) rays={} rotation_period={} s time_per_ray={} s "
      "lcm_url={} truth_channel={} channel={} noise_seed={}",
      setup->scenario.name, setup->scenario.seed, setup->scene.name,
      setup->scene.mesh.triangles.size(), rays.size(), sensor.rotation_period, sensor.time_per_ray,
      lcm_url, truth_channel, channel, seed);

  std::deque<Sample> samples;
  (*bus)->Subscribe(truth_channel, [&](const selfcal::BusMessage& message) {
    auto state = selfcal::DecodeLcm<selfcal::joint_state_t>(message.data, message.channel);
    if (!state || state->positions.size() != truth.JointCount()) return;
    if (!samples.empty() && state->utime <= samples.back().utime) return;
    samples.push_back({state->utime, state->positions});
    while (samples.size() > 4000) samples.pop_front();
  });
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  std::mt19937_64 random(seed);
  std::normal_distribution<double> gaussian(0.0, 1.0);
  const auto period_us = static_cast<std::int64_t>(std::llround(sensor.rotation_period * 1e6));
  const auto span_us = static_cast<std::int64_t>(
      std::ceil((static_cast<double>(rays.size()) - 1) * sensor.time_per_ray * 1e6));
  std::int64_t next_start = 0, counter = 0, published = 0, skipped = 0;
  selfcal::range_scan_t scan;
  scan.device_utime = -1;
  scan.time_per_ray = sensor.time_per_ray;
  scan.angle_first = sensor.angle_first;
  scan.angle_increment = sensor.angle_increment;
  scan.num_ranges = static_cast<std::int32_t>(rays.size());
  scan.num_intensities = 0;
  std::vector<double> q;
  while (!g_stop) {
    auto handled = (*bus)->HandleOnce(std::chrono::milliseconds(5));
    if (!handled) return Fail(handled.error().message);
    if (samples.size() < 2) continue;
    if (next_start == 0) next_start = samples.back().utime;
    // A rotation is cast once the true joint states cover all of it.
    while (samples.back().utime >= next_start + span_us) {
      scan.utime = next_start;
      scan.scan_counter = counter++;
      scan.ranges.assign(rays.size(), std::nanf(""));
      bool complete = true;
      for (std::size_t i = 0; i < rays.size() && complete; ++i) {
        const auto t = next_start + static_cast<std::int64_t>(std::llround(
                                        static_cast<double>(i) * sensor.time_per_ray * 1e6));
        if (!Interpolate(samples, t, q)) {
          complete = false;
          break;
        }
        const auto T_base_sensor = selfcal::ForwardKinematics(truth, q);
        const double range = (*caster)->Cast(
            T_base_sensor.translation(), T_base_sensor.linear() * rays[i], sensor.range_max * 1.1);
        if (!std::isfinite(range)) continue;
        const double noisy = range + sensor.Sigma(range) * gaussian(random);
        if (noisy >= sensor.range_min && noisy <= sensor.range_max)
          scan.ranges[i] = static_cast<float>(noisy);
      }
      if (complete) {
        (void)(*bus)->Publish(channel, scan);
        ++published;
      } else {
        ++skipped;
      }
      next_start += period_us;
      // Fell behind (a pause in the truth stream): restart at the newest sample.
      if (samples.back().utime - next_start > 10 * period_us) next_start = samples.back().utime;
    }
  }
  spdlog::info("stopping: {} rotations published, {} skipped (joint states missing)", published,
               skipped);
  return 0;
}
