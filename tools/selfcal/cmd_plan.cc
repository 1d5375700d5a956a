// `selfcal plan SCENARIO.yaml --out DIR [--max-scans N] [--target-mm X] [--candidates N]`:
// chooses the fit scans by information (core/plan/information_planner.h) among the scenario's
// candidate views, and writes the plan file selfcald executes (DIR/plan.yaml, the format of
// daemon/plan.h, through its writer) and the nominal model (DIR/nominal.yaml). The scene is
// the scenario's, or with --map-log a map of the site from an earlier session's scans
// (core/sim/site_map.h); the robot, its joint limits and the sensor are the scenario's files.
#include <spdlog/spdlog.h>

#include <cstdio>
#include <filesystem>

#include "core/plan/information_planner.h"
#include "core/sim/site_map.h"
#include "core/util/atomic_file.h"
#include "daemon/plan.h"
#include "protocols/model_file/model_file.h"
#include "protocols/model_file/sensor_config.h"
#include "protocols/recording/recording.h"
#include "protocols/report/fused_cloud.h"
#include "protocols/scenario/scenario_file.h"
#include "protocols/scenario/simulation_setup.h"
#include "tools/selfcal/cli_util.h"
#include "tools/selfcal/commands.h"

namespace selfcal::cli {
namespace {

struct PlanCommandOptions {
  std::string scenario;
  std::string out;
  int max_scans = 28;
  double target_mm = 0;
  int candidates = 0;
  int validation_scans = -1;
  int threads = 0;
  std::int64_t seed = -1;
  std::string map_log;    // an earlier session's recording: the scene is its map
  std::string map_robot;  // the model its scans are fused with; empty = the scenario's nominal
  double map_voxel_m = sim::SiteMapOptions{}.surface_voxel_m;
};

// Points enough for a room at the map's 2 cm (a 5 x 5 x 3 m room's surfaces hold about 250,000
// voxels); more only cost time.
constexpr std::size_t kMapPoints = 4'000'000;

// Replaces the scenario's surfaces by the map of `args.map_log`'s scans, fused in the base frame
// with `args.map_robot` (or `nominal`).
Status UseMapOf(const PlanCommandOptions& args, const SensorConfig& sensor,
                const RobotModel& nominal, sim::Scene& scene) {
  RobotModel model = nominal;
  if (!args.map_robot.empty()) {
    auto file = ReadModelFile(args.map_robot);
    if (!file) return file.error();
    model = std::move(file->model);
  }
  auto datasets = recording::LoadRecording(args.map_log, model, sensor);
  if (!datasets) return datasets.error();
  const auto fused = report::FuseScans(*datasets, model, report::ScanSelection::kAll, kMapPoints);
  std::vector<Eigen::Vector3f> points;
  points.reserve(fused.size());
  for (const auto& p : fused) points.emplace_back(p.x, p.y, p.z);
  sim::SiteMapOptions map_options;
  map_options.surface_voxel_m = args.map_voxel_m;
  sim::SiteMap map = sim::BuildSiteMap(points, map_options);
  spdlog::info(
      "plan: the scene is the map of {} ({} scans, {} points): {} squares of {:.0f} mm, {} "
      "occupied voxels of {:.0f} mm",
      args.map_log, datasets->size(), map.points, map.splats, map_options.surface_voxel_m * 1e3,
      map.occupied.size(), map_options.occupancy_voxel_m * 1e3);
  if (map.splats == 0) return Error{args.map_log + ": no surface in its scans to plan on"};
  sim::UseSiteMap(std::move(map), scene);
  return OkStatus();
}

void PrintSummary(const plan::CandidateSet& candidates, const plan::InformationPlan& planned,
                  const plan::PlannerOptions& options) {
  for (const auto& finding : candidates.unobservable)
    std::printf("warning: %s (masked: the scene cannot determine it)\n", finding.c_str());
  const plan::Thinning& thinning = candidates.thinning;
  const std::string resolution =
      candidates.views.empty() || candidates.views.front().start == candidates.views.front().end
          ? "the camera binned " + std::to_string(thinning.along)
          : "1 point in " + std::to_string(thinning.along) + " along a line, 1 line in " +
                std::to_string(thinning.lines);
  std::printf(
      "candidates: %zu views, %zu see the scene, %zu with links colliding, %zu pairs overlap "
      "(planned on %s)\n",
      candidates.views.size(), candidates.sighted.size(), candidates.colliding.size(),
      candidates.information.pairs.size(), resolution.c_str());
  std::printf("chosen: %zu fit scans + %zu validation scans\n", planned.chosen.size(),
              candidates.validation.size());
  std::printf(
      "predicted sensor position error: %.4f mm RMS, %.4f mm worst (naive covariance of "
      "noise-free scans, match sigma %.2f mm; %.4f mm RMS of it from the intrinsics the "
      "calibration holds)\n",
      planned.predicted.sensor.rms_position_m * 1e3, planned.predicted.sensor.max_position_m * 1e3,
      candidates.sigma_m * 1e3, planned.predicted_held.sensor.rms_position_m * 1e3);
  if (options.target_m > 0) {
    std::printf("target %.4f mm: %s\n", options.target_m * 1e3,
                planned.target_met ? "met" : "not met within --max-scans");
  }
  std::printf("planning time: %.1f s (candidates %.1f s, selection %.1f s)\n",
              candidates.seconds + planned.seconds, candidates.seconds, planned.seconds);
}

int RunPlan(const PlanCommandOptions& args) {
  plan::PlannerOptions options;
  options.max_scans = args.max_scans;
  options.min_scans = std::min(3, args.max_scans);
  options.target_m = args.target_mm * 1e-3;
  options.candidates = args.candidates;
  options.threads = args.threads;
  if (std::string problem; !options.IsValid(&problem)) return Fail(problem, 2);
  if (!args.map_robot.empty() && args.map_log.empty())
    return Fail("--map-robot names the model of --map-log's scans: give --map-log too", 2);
  auto scenario = ReadScenarioFile(args.scenario);
  if (!scenario) return Fail(scenario.error().message);
  if (args.validation_scans >= 0) scenario->plan.validation_scans = args.validation_scans;
  if (args.seed >= 0) scenario->seed = scenario->plan.seed = static_cast<std::uint64_t>(args.seed);
  if (scenario->scene.kind == sim::SceneSpec::Kind::kCell && args.map_log.empty()) {
    return Fail(args.scenario +
                ": a cell's free space has nothing to see; plan on a map of an earlier "
                "session's scans there (--map-log RECORDING --map-robot ITS_RESULT). No session "
                "yet: survey the cell with its paper-style plan first (selfcal daemon-plan " +
                args.scenario + " --out DIR, run it with selfcald), then plan on that recording");
  }
  // A cell (free space only) has nothing to see: its map gives it surfaces.
  auto setup =
      PrepareSimulation(std::move(scenario).value(),
                        args.map_log.empty() ? SetupUse::kSimulation : SetupUse::kPlanningOnly);
  if (!setup) return Fail(setup.error().message);
  auto sensor = ReadSensorConfig(setup->scenario.sensor_path);
  if (!sensor) return Fail(sensor.error().message);
  calib::CalibrationOptions engine = recording::CalibrationOptionsFromSensor(*sensor);
  if (!args.map_log.empty()) {
    if (auto used = UseMapOf(args, *sensor, setup->nominal, setup->scene); !used)
      return Fail(used.error().message);
  }
  const auto progress = [](const std::string& line) { spdlog::info("plan: {}", line); };
  auto candidates = plan::MakeCandidates(setup->nominal, setup->sensor, setup->scene,
                                         setup->scenario.plan, engine, options, progress);
  if (!candidates) return Fail(args.scenario + ": " + candidates.error().message);
  plan::InformationPlan planned = plan::ChooseScans(*candidates, options, progress);
  if (planned.chosen.size() < 2)
    return Fail(args.scenario + ": no two candidate views overlap; nothing to plan");
  const double chosen_travel = sim::JointTravel(planned.plan);
  const std::size_t chosen_blocked =
      sim::BlockedMoves(setup->nominal, setup->scene, planned.plan, options.link_radius).size();
  auto ordered = sim::OrderForFreeMoves(setup->nominal, setup->scene, std::move(planned.plan),
                                        options.link_radius);
  if (!ordered) return Fail(args.scenario + ": " + ordered.error().message);
  planned.plan = std::move(*ordered);
  spdlog::info(
      "plan: scans ordered so that every move between them keeps the links {:.2f} m clear: joint "
      "travel {:.0f} deg ({:.0f} deg in the order chosen, where {} moves would hit the scene)",
      options.link_radius, sim::JointTravel(planned.plan) * 180 / M_PI, chosen_travel * 180 / M_PI,
      chosen_blocked);
  std::error_code error;
  std::filesystem::create_directories(args.out, error);
  if (error) return Fail(args.out + ": cannot create the folder: " + error.message());
  const std::filesystem::path out(args.out);
  const std::string text = daemon::FormatScanPlan(
      daemon::FromSimulatedPlan(setup->scenario.name, planned.plan),
      "From " + args.scenario + " (seed " + std::to_string(setup->scenario.seed) +
          ") by selfcal plan: " + std::to_string(planned.chosen.size()) +
          " fit scans chosen by information among " + std::to_string(candidates->views.size()) +
          " views.");
  if (auto s = WriteFileAtomically((out / "plan.yaml").string(), text); !s)
    return Fail(s.error().message);
  if (auto s = WriteModelFile(
          (out / "nominal.yaml").string(), setup->nominal,
          "role: nominal\nsource: selfcal plan\nscenario: " + setup->scenario.name + "\n");
      !s) {
    return Fail(s.error().message);
  }
  PrintSummary(*candidates, planned, options);
  return 0;
}

}  // namespace

void RegisterPlan(CLI::App& app) {
  auto* command = app.add_subcommand(
      "plan",
      "Choose scans by information: the views of a scenario whose scans pin the calibrated "
      "parameters down best (plan.yaml for selfcald, nominal.yaml)");
  auto options = std::make_shared<PlanCommandOptions>();
  AddScenarioFile(command, options->scenario);
  command->add_option("--out", options->out, "Output folder")->required();
  command->add_option("--max-scans", options->max_scans, "Fit scans at most (default 28)");
  command->add_option("--target-mm", options->target_mm,
                      "Stop adding scans once the predicted sensor position error (RMS over the "
                      "joint space) is below this; 0 = plan --max-scans (default)");
  command->add_option("--candidates", options->candidates,
                      "Candidate views to choose from (default 3 x --max-scans)");
  command->add_option("--validation-scans", options->validation_scans,
                      "Validation scans (default: the scenario's)");
  command
      ->add_option("--seed", options->seed,
                   "Seed of the candidate views (as `selfcal simulate --seed`); default: the "
                   "scenario's")
      ->check(CLI::NonNegativeNumber);
  command->add_option("--threads", options->threads, "Worker threads (0 = all cores)")
      ->check(CLI::NonNegativeNumber);
  AddOptionalInputFile(
      command, "--map-log", options->map_log,
      "Plan on the site as an earlier session's recording saw it: its scans fused into "
      "a map replace the scenario's surfaces (docs/planning.md)");
  AddOptionalInputFile(
      command, "--map-robot", options->map_robot,
      "The model that recording's scans are fused with (its session's result); default: "
      "the scenario's nominal model");
  command
      ->add_option("--map-voxel", options->map_voxel_m,
                   "The map's surface spacing [m] (default 0.02)")
      ->check(CLI::Range(0.005, 0.2));
  command->callback([options] { exit_code = RunPlan(*options); });
}

}  // namespace selfcal::cli
