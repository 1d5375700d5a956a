// `selfcal simulate SCENARIO.yaml --out DIR [--scans N | --plan FILE] [--seed N] [--threads N]`:
// runs a simulation scenario and writes DIR/recording.lcmlog (docs/recording.md), DIR/truth.yaml
// and DIR/nominal.yaml (robot model files, sensor mount included in the tool) and DIR/scenario.yaml
// (the resolved scenario with its seed). Same seed, same bytes, whatever the thread count.
#include <spdlog/spdlog.h>
#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>

#include "core/model/evaluation.h"
#include "core/sim/ground_truth.h"
#include "core/sim/ray_caster.h"
#include "core/sim/scan_plan.h"
#include "core/sim/simulator.h"
#include "core/util/atomic_file.h"
#include "daemon/plan.h"
#include "protocols/lcm_log/lcm_log.h"
#include "protocols/model_file/model_file.h"
#include "protocols/scenario/scenario_file.h"
#include "protocols/scenario/sensor_model_config.h"
#include "protocols/scenario/sim_messages.h"
#include "protocols/scenario/simulation_setup.h"
#include "tools/selfcal/cli_util.h"
#include "tools/selfcal/commands.h"
#include "tools/selfcal/pose_error_text.h"
#include "tools/selfcal/progress.h"

namespace selfcal::cli {
namespace {

struct SimulateOptions {
  std::string scenario_path;
  std::string out_dir;
  int scans = -1;
  std::int64_t seed = -1;
  int threads = 0;
  std::string plan;  // a plan file (daemon/plan.h) instead of the scenario's generator
};

// The scenario generator's plan, or with --plan the plan file's scans (checked against the
// nominal model as selfcald checks them, margin 0).
Expected<sim::ScanPlan> ScanPlanFor(const SimulateOptions& options, const SimulationSetup& setup) {
  if (options.plan.empty()) {
    auto plan = sim::MakeScanPlan(setup.nominal, setup.sensor, setup.scene, setup.scenario.plan);
    if (!plan) return Error{options.scenario_path + ": " + plan.error().message};
    return plan;
  }
  auto file = daemon::ReadScanPlan(options.plan);
  if (!file) return file.error();
  if (const std::string problem = daemon::CheckPlan(*file, setup.nominal, 0.0); !problem.empty())
    return Error{options.plan + ": " + problem};
  return daemon::ToSimulatedPlan(*file);
}

int RunSimulate(const SimulateOptions& options) {
  const auto wall_start = std::chrono::steady_clock::now();
  auto scenario_or = ReadScenarioFile(options.scenario_path);
  if (!scenario_or) return Fail(scenario_or.error().message);
  Scenario scenario = std::move(*scenario_or);
  if (options.seed >= 0) {
    scenario.seed = static_cast<std::uint64_t>(options.seed);
    scenario.plan.seed = scenario.seed;
    scenario.recording.seed = scenario.seed;
  }
  if (options.scans >= 0) {
    if (options.scans < 1 || options.scans > 1000) return Fail("--scans must be in 1..1000");
    scenario.plan.fit_scans = options.scans;
  }

  // Before any work: an unusable output folder is bad input.
  std::error_code error;
  std::filesystem::create_directories(options.out_dir, error);
  if (error) return Fail(options.out_dir + ": cannot create the folder: " + error.message());
  const std::filesystem::path out(options.out_dir);
  if (std::filesystem::exists(out / "recording.lcmlog", error)) {
    spdlog::warn(
        "simulate: {} holds a simulation already: its recording.lcmlog, truth.yaml, "
        "nominal.yaml and scenario.yaml are replaced",
        options.out_dir);
  }

  auto setup_or = PrepareSimulation(std::move(scenario));
  if (!setup_or) return Fail(setup_or.error().message);
  const SimulationSetup& setup = *setup_or;
  const Scenario& resolved = setup.scenario;
  const sim::SensorModel& sensor = setup.sensor;

  std::optional<tbb::global_control> thread_limit;
  if (options.threads > 0) {
    thread_limit.emplace(tbb::global_control::max_allowed_parallelism,
                         static_cast<std::size_t>(options.threads));
  }

  spdlog::info("simulate: scenario={} seed={} fit_scans={} validation_scans={}", resolved.name,
               resolved.seed, resolved.plan.fit_scans, resolved.plan.validation_scans);
  spdlog::info("simulate: robot={} sensor={} ({} {}x{}) out={} threads={}", resolved.robot_path,
               resolved.sensor_path, kSensorLayoutNames.Name(sensor.kind), sensor.width,
               sensor.height, options.out_dir,
               options.threads > 0 ? std::to_string(options.threads) : "all");
  spdlog::info(
      "simulate: joint_rate_hz={} encoder_noise={} timestamp_jitter={} latency={} target_rms_m={}",
      resolved.recording.joint_rate_hz, resolved.recording.encoder_noise,
      resolved.recording.timestamp_jitter, resolved.recording.latency,
      resolved.truth.target_position_rms);
  if (resolved.recording.effects.AnyEnabled()) {
    spdlog::info("simulate: field effects on (listed in scenario.yaml under effects:)");
  }

  auto caster = sim::RayCaster::Create(setup.scene);
  if (!caster) return Fail(caster.error().message);
  spdlog::info("simulate: scene {}: {} triangles", setup.scene.name,
               setup.scene.mesh.triangles.size());
  const RobotModel& nominal = setup.nominal;
  const RobotModel& truth = setup.truth;
  const PoseErrorStats initial_error =
      SensorPoseError(truth, nominal, kEvaluationSamples, kEvaluationSeed);
  spdlog::info("simulate: nominal vs truth, sensor, {}: {}",
               SampleSetText(kEvaluationSamples, kEvaluationSeed), PoseErrorText(initial_error));

  auto plan = ScanPlanFor(options, setup);
  if (!plan) return Fail(plan.error().message);

  MessageContext context;
  context.start_utime = resolved.start_utime;
  for (const auto& joint : nominal.joints) context.joint_names.push_back(joint.name);
  context.plan_name = resolved.name;
  context.session_id = "sim-" + resolved.name + "-" + std::to_string(resolved.seed);
  context.sensor = sensor;
  context.camera_output = resolved.camera_output;

  const sim::Simulator simulator(truth, sensor, **caster, *plan, resolved.recording);
  auto writer = LcmLogWriter::Open((out / "recording.lcmlog").string());
  if (!writer) return Fail(writer.error().message);
  std::size_t events = 0, frames = 0, points = 0, valid = 0;
  {  // the bar ends before the summary is logged
    Progress progress(Progress::ModeFor());
    const int segments = simulator.SegmentCount();
    for (int k = 0; k < segments; ++k) {
      progress.Update("simulating", static_cast<double>(k) / segments,
                      "segment " + std::to_string(k + 1) + " of " + std::to_string(segments) +
                          " (scans and the moves between them)");
      const sim::SimSegment segment = simulator.Segment(k);
      frames += segment.frames.size();
      for (const auto& frame : segment.frames) {
        points += frame.ranges.size() + frame.points.size();
        for (float r : frame.ranges) valid += std::isnan(r) ? 0 : 1;
        for (const auto& p : frame.points) valid += std::isnan(p.z()) ? 0 : 1;
      }
      for (const auto& event : SegmentEvents(segment, context)) {
        if (auto status = writer->Write(event.channel, event.utime, event.data); !status) {
          return Fail(status.error().message);
        }
        ++events;
      }
      spdlog::debug("simulate: scan {} done: {} frames", k, segment.frames.size());
    }
  }
  if (auto status = writer->Commit(); !status) return Fail(status.error().message);

  std::ostringstream provenance;
  provenance << "source: selfcal simulate\nscenario: " << resolved.name
             << "\nseed: " << resolved.seed << "\nevaluation_samples: " << kEvaluationSamples
             << "\nevaluation_seed: " << kEvaluationSeed
             << "\nnominal_sensor_position_rms_mm: " << initial_error.rms_position_m * 1e3
             << "\nnominal_sensor_orientation_rms_deg: "
             << initial_error.rms_orientation_rad * 180 / std::numbers::pi << "\n";
  if (auto s =
          WriteModelFile((out / "truth.yaml").string(), truth, "role: truth\n" + provenance.str());
      !s) {
    return Fail(s.error().message);
  }
  if (auto s = WriteModelFile((out / "nominal.yaml").string(), nominal,
                              "role: nominal\n" + provenance.str());
      !s) {
    return Fail(s.error().message);
  }
  if (auto s = WriteFileAtomically((out / "scenario.yaml").string(), FormatScenario(resolved));
      !s) {
    return Fail(s.error().message);
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  spdlog::info(
      "simulate: wrote {} events ({} sensor frames, {} of {} points valid, {:.1f} s simulated) in "
      "{:.1f} s",
      events, frames, valid, points, simulator.Duration(), seconds);
  std::cout << (out / "recording.lcmlog").string() << "\n";
  return 0;
}

}  // namespace

void RegisterSimulate(CLI::App& app) {
  auto* command = app.add_subcommand(
      "simulate", "Simulate a scenario: recording.lcmlog, truth.yaml, nominal.yaml, scenario.yaml");
  auto options = std::make_shared<SimulateOptions>();
  AddScenarioFile(command, options->scenario_path);
  command
      ->add_option(
          "--out", options->out_dir,
          "Output folder (created if missing; a simulation in it is replaced, with a warning)")
      ->required();
  auto* scans = command->add_option("--scans", options->scans,
                                    "Number of fitted scans (7, 14, 21, 28, ...); "
                                    "default: the scenario's");
  AddOptionalInputFile(command, "--plan", options->plan,
                       "Scan plan file (selfcal plan's or daemon-plan's plan.yaml) to simulate "
                       "instead of the scenario's plan generator")
      ->excludes(scans);
  command->add_option("--seed", options->seed, "Seed; default: the scenario's")
      ->check(CLI::NonNegativeNumber);
  command->add_option("--threads", options->threads, "Worker threads (0 = all cores)")
      ->check(CLI::NonNegativeNumber);
  command->callback([options] { exit_code = RunSimulate(*options); });
}

}  // namespace selfcal::cli
