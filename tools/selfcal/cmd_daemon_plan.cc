// `selfcal daemon-plan SCENARIO.yaml --out DIR [--scans N] [--validation-scans N]
// [--mode remaster] [--swap JOINT=DEG ...]`: turns a scenario's scan plan (core/sim MakeScanPlan,
// the paper's protocols) into a plan file selfcald executes (DIR/plan.yaml), and writes the
// nominal model (DIR/nominal.yaml; sensor mount in the tool) and the resolved scenario. A real
// cell is described by a scenario whose scene is `kind: cell` (its free space only); any other
// scene is simulated, and its true model is written too (DIR/truth.yaml). `--mode remaster`
// writes a quick remastering's plan (`mode: remaster`, 6 fit scans unless --scans says
// otherwise); `--swap` simulates a motor swap (the scenario's truth.joint_offsets) and writes
// the truth before it as DIR/installed.yaml.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/plan/information_planner.h"
#include "core/sim/scan_plan.h"
#include "core/util/atomic_file.h"
#include "daemon/plan.h"
#include "protocols/model_file/model_file.h"
#include "protocols/scenario/scenario_file.h"
#include "protocols/scenario/simulation_setup.h"
#include "tools/selfcal/cli_util.h"
#include "tools/selfcal/commands.h"

namespace selfcal::cli {
namespace {

struct DaemonPlanOptions {
  std::string scenario;
  std::string out;
  int scans = -1;
  int validation_scans = -1;
  std::string mode = "full";
  std::vector<std::string> swaps;  // JOINT=DEG
};

// The fit scans of a quick remastering: about 6 (docs/daemon.md).
constexpr int kRemasterFitScans = 6;

// `--swap JOINT=DEG` into the scenario's truth.joint_offsets (rad), by the robot file's names.
Status ApplySwaps(const std::vector<std::string>& swaps, Scenario& scenario) {
  if (swaps.empty()) return OkStatus();
  const auto robot = ReadModelFile(scenario.robot_path);
  if (!robot) return robot.error();
  const RobotModel& model = robot->model;
  if (scenario.truth_joint_offsets.empty())
    scenario.truth_joint_offsets.assign(model.JointCount(), 0);
  for (const std::string& swap : swaps) {
    const auto equal = swap.find('=');
    std::size_t joint = 0;
    while (joint < model.JointCount() && model.joints[joint].name != swap.substr(0, equal)) ++joint;
    char* end = nullptr;
    const double degrees =
        equal == std::string::npos ? NAN : std::strtod(swap.c_str() + equal + 1, &end);
    if (joint == model.JointCount() || !std::isfinite(degrees) || end == nullptr || *end != 0 ||
        model.joints[joint].type != JointType::kRevolute) {
      return Error{"--swap '" + swap + "': want JOINT=DEGREES with a revolute joint of " +
                   scenario.robot_path + ", e.g. A4=0.5"};
    }
    scenario.truth_joint_offsets[joint] += degrees * M_PI / 180;
  }
  return OkStatus();
}

// Without plan.link_radius the generator keeps only the sensor's origin clear: say where the
// links, as `selfcal plan` checks them, would not be, so that whoever installs the plan knows
// which moves to watch, or sets plan.link_radius.
void WarnOfLinksNotClear(const RobotModel& model, const sim::Scene& scene,
                         const sim::ScanPlan& plan) {
  const double link_radius = plan::PlannerOptions{}.link_radius;  // as `selfcal plan` checks
  std::vector<std::string> moves, scans;
  for (std::size_t k = 0; k < plan.scans.size(); ++k) {
    if (!sim::LinksAreFree(model, scene, plan.scans[k].start, link_radius))
      scans.push_back(std::to_string(k + 1));
  }
  for (std::size_t k : sim::BlockedMoves(model, scene, plan, link_radius))
    moves.push_back(std::to_string(k) + "->" + std::to_string(k + 1));
  if (moves.empty() && scans.empty()) return;
  auto listed = [](const std::vector<std::string>& items) {
    std::string text;
    for (const auto& item : items) text += (text.empty() ? "" : ", ") + item;
    return text.empty() ? std::string("none") : text;
  };
  spdlog::warn(
      "daemon-plan: the links, as capsules of {} m, leave the free space or enter a box at {} of "
      "{} scans (at scans: {}) and on {} of {} moves between scans (scans {}); without "
      "plan.link_radius this planner keeps the sensor's origin clear only: set it (docs/"
      "simulation.md), or watch those moves on the first run",
      link_radius, scans.size(), plan.scans.size(), listed(scans), moves.size(),
      plan.scans.size() - 1, listed(moves));
}

int RunDaemonPlan(const DaemonPlanOptions& options) {
  auto scenario = ReadScenarioFile(options.scenario);
  if (!scenario) return Fail(scenario.error().message);
  if (options.mode != "full" && options.mode != "remaster") {
    return Fail("--mode must be full or remaster, not '" + options.mode + "'", program::kExitUsage);
  }
  const bool remaster = options.mode == "remaster";
  if (options.scans > 0) {
    scenario->plan.fit_scans = options.scans;
  } else if (remaster) {
    scenario->plan.fit_scans = kRemasterFitScans;
  }
  const bool cell = scenario->scene.kind == sim::SceneSpec::Kind::kCell;
  if (cell && !options.swaps.empty()) {
    return Fail("--swap simulates a motor swap, and " + options.scenario +
                    " describes a real cell (scene kind cell): nothing to simulate",
                program::kExitUsage);
  }
  if (auto swapped = ApplySwaps(options.swaps, *scenario); !swapped) {
    return Fail(swapped.error().message);
  }
  if (options.validation_scans > 0) scenario->plan.validation_scans = options.validation_scans;
  auto setup = PrepareSimulation(std::move(scenario).value(), SetupUse::kPlanningOnly);
  if (!setup) return Fail(setup.error().message);
  auto plan = sim::MakeScanPlan(setup->nominal, setup->sensor, setup->scene, setup->scenario.plan);
  if (!plan) return Fail(options.scenario + ": " + plan.error().message);
  if (setup->scenario.plan.link_radius == 0)
    WarnOfLinksNotClear(setup->nominal, setup->scene, *plan);
  daemon::ScanPlan daemon_plan =
      daemon::FromSimulatedPlan(setup->scenario.name + (remaster ? "-remaster" : ""), *plan);
  if (remaster) daemon_plan.mode = daemon::PlanMode::kRemaster;
  const std::string text = daemon::FormatScanPlan(
      daemon_plan, "From " + options.scenario + " (seed " + std::to_string(setup->scenario.seed) +
                       ") by selfcal daemon-plan: " + std::to_string(plan->scans.size()) +
                       " scans.");
  std::error_code error;
  std::filesystem::create_directories(options.out, error);
  if (error) return Fail(options.out + ": cannot create the folder: " + error.message());
  const std::filesystem::path out(options.out);
  if (auto s = WriteFileAtomically((out / "plan.yaml").string(), text); !s)
    return Fail(s.error().message);
  const std::string provenance = "source: selfcal daemon-plan\nscenario: " + setup->scenario.name +
                                 "\nseed: " + std::to_string(setup->scenario.seed) + "\n";
  if (auto s = WriteModelFile((out / "nominal.yaml").string(), setup->nominal,
                              "role: nominal\n" + provenance);
      !s) {
    return Fail(s.error().message);
  }
  if (!cell) {
    if (auto s = WriteModelFile((out / "truth.yaml").string(), setup->truth,
                                "role: truth\n" + provenance);
        !s) {
      return Fail(s.error().message);
    }
  }
  if (!setup->scenario.truth_joint_offsets.empty()) {
    if (auto s =
            WriteModelFile((out / "installed.yaml").string(), setup->installed,
                           "role: installed (the truth before the swap of --swap)\n" + provenance);
        !s) {
      return Fail(s.error().message);
    }
  }
  if (auto s =
          WriteFileAtomically((out / "scenario.yaml").string(), FormatScenario(setup->scenario));
      !s) {
    return Fail(s.error().message);
  }
  spdlog::info("daemon-plan: {} scans of scenario {} (seed {}) -> {}", plan->scans.size(),
               setup->scenario.name, setup->scenario.seed, (out / "plan.yaml").string());
  return 0;
}

}  // namespace

void RegisterDaemonPlan(CLI::App& app) {
  auto* command = app.add_subcommand(
      "daemon-plan",
      "A selfcald scan plan from a cell (a scenario with scene kind cell) or a simulation "
      "scenario: plan.yaml, nominal.yaml (and truth.yaml when simulated)");
  auto options = std::make_shared<DaemonPlanOptions>();
  AddScenarioFile(command, options->scenario);
  command->add_option("--out", options->out, "Output folder")->required();
  command->add_option("--scans", options->scans, "Fitted scans (default: the scenario's)");
  command->add_option("--validation-scans", options->validation_scans,
                      "Validation scans (default: the scenario's)");
  command->add_option("--mode", options->mode,
                      "full, or remaster: a quick remastering's plan (mode: remaster; 6 fit scans "
                      "unless --scans), docs/daemon.md");
  command->add_option("--swap", options->swaps,
                      "JOINT=DEG: a simulated motor swap, the true arm's JOINT zero turned by DEG "
                      "degrees (repeatable); also writes installed.yaml, the truth before it");
  command->callback([options] { exit_code = RunDaemonPlan(*options); });
}

}  // namespace selfcal::cli
