// `selfcal daemon-plan SCENARIO.yaml --out DIR [--scans N] [--validation-scans N]`: turns a
// simulation scenario's scan plan (core/sim MakeScanPlan, the paper's protocols) into a plan
// file selfcald executes (DIR/plan.yaml), and writes the scenario's nominal and true models
// (DIR/nominal.yaml, DIR/truth.yaml; sensor mount in the tool) and the resolved scenario.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

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
};

int RunDaemonPlan(const DaemonPlanOptions& options) {
  auto scenario = ReadScenarioFile(options.scenario);
  if (!scenario) return Fail(scenario.error().message);
  if (options.scans > 0) scenario->plan.fit_scans = options.scans;
  if (options.validation_scans > 0) scenario->plan.validation_scans = options.validation_scans;
  auto setup = PrepareSimulation(std::move(scenario).value());
  if (!setup) return Fail(setup.error().message);
  auto plan = sim::MakeScanPlan(setup->nominal, setup->sensor, setup->scene, setup->scenario.plan);
  if (!plan) return Fail(options.scenario + ": " + plan.error().message);
  const std::string text = daemon::FormatScanPlan(
      daemon::FromSimulatedPlan(setup->scenario.name, *plan),
      "From " + options.scenario + " (seed " + std::to_string(setup->scenario.seed) +
          ") by selfcal daemon-plan: " + std::to_string(plan->scans.size()) + " scans.");
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
  if (auto s =
          WriteModelFile((out / "truth.yaml").string(), setup->truth, "role: truth\n" + provenance);
      !s) {
    return Fail(s.error().message);
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
      "A selfcald scan plan from a simulation scenario (plan.yaml, nominal.yaml, truth.yaml)");
  auto options = std::make_shared<DaemonPlanOptions>();
  command->add_option("scenario", options->scenario, "Scenario file (config/scenarios/*.yaml)")
      ->check(kFileNotFolder)
      ->required();
  command->add_option("--out", options->out, "Output folder")->required();
  command->add_option("--scans", options->scans, "Fitted scans (default: the scenario's)");
  command->add_option("--validation-scans", options->validation_scans,
                      "Validation scans (default: the scenario's)");
  command->callback([options] { exit_code = RunDaemonPlan(*options); });
}

}  // namespace selfcal::cli
