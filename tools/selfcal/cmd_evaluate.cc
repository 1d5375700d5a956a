// `selfcal evaluate --truth TRUTH.yaml --model MODEL.yaml [--samples 500] [--seed N] [--json]`:
// pose error of a model against a reference over random configurations (core/model/evaluation.h).
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>

#include "core/model/evaluation.h"
#include "protocols/model_file/model_file.h"
#include "tools/selfcal/cli_util.h"
#include "tools/selfcal/commands.h"
#include "tools/selfcal/pose_error_text.h"

namespace selfcal::cli {
namespace {

constexpr double kMmPerM = 1000.0;
constexpr double kDegPerRad = 180.0 / std::numbers::pi;

void PrintText(const char* label, const PoseErrorStats& s) {
  std::printf("%-7s %s\n", label, PoseErrorText(s).c_str());
}

void PrintJson(const char* label, const PoseErrorStats& s, bool last) {
  std::printf(
      "  \"%s\": {\"rms_position_mm\": %.9g, \"max_position_mm\": %.9g, "
      "\"rms_orientation_deg\": %.9g, \"max_orientation_deg\": %.9g}%s\n",
      label, s.rms_position_m * kMmPerM, s.max_position_m * kMmPerM,
      s.rms_orientation_rad * kDegPerRad, s.max_orientation_rad * kDegPerRad, last ? "" : ",");
}

}  // namespace

void RegisterEvaluate(CLI::App& app) {
  auto* command = app.add_subcommand(
      "evaluate",
      "Pose error of a model against a reference model over random configurations within the "
      "joint limits: T_base_sensor, and the paper's flange comparison (base, tool and "
      "uncalibrated parameters taken from the truth)");
  struct Options {
    std::string truth;
    std::string model;
    std::size_t samples = kEvaluationSamples;
    std::uint64_t seed = kEvaluationSeed;
    bool json = false;
  };
  auto options = std::make_shared<Options>();
  AddInputFile(command, "--truth", options->truth, "Reference robot model file (YAML)");
  AddInputFile(command, "--model", options->model, "Robot model file to evaluate (YAML)");
  command->add_option("--samples", options->samples, "Number of random configurations")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{1}, std::size_t{100000000}));
  command->add_option("--seed", options->seed, "Seed of the configuration generator")
      ->capture_default_str();
  command->add_flag("--json", options->json, "Print JSON instead of text");
  command->callback([options] {
    spdlog::info("evaluate: truth={} model={} samples={} seed={} json={}", options->truth,
                 options->model, options->samples, options->seed, options->json);
    const auto truth = ReadModelFile(options->truth);
    if (!truth) {
      exit_code = Fail(truth.error().message);
      return;
    }
    const auto model = ReadModelFile(options->model);
    if (!model) {
      exit_code = Fail(model.error().message);
      return;
    }
    const std::string problem = CheckComparable(truth->model, model->model);
    if (!problem.empty()) {
      exit_code = Fail(options->truth + " and " + options->model + " differ: " + problem);
      return;
    }
    for (std::size_t i = 0; i < truth->model.JointCount(); ++i) {
      const JointSpec& a = truth->model.joints[i];
      const JointSpec& b = model->model.joints[i];
      if (a.lower != b.lower || a.upper != b.upper) {
        spdlog::warn("joint {}: limits differ; configurations are drawn within the truth's",
                     a.name);
      }
    }
    const ModelComparison c =
        CompareModels(truth->model, model->model, options->samples, options->seed);
    if (options->json) {
      std::printf("{\n  \"samples\": %zu,\n  \"seed\": %llu,\n", c.samples,
                  static_cast<unsigned long long>(c.seed));
      PrintJson("sensor", c.sensor, false);
      PrintJson("flange", c.flange, true);
      std::printf("}\n");
    } else {
      std::printf("%s\n", SampleSetText(c.samples, c.seed).c_str());
      PrintText("sensor", c.sensor);
      PrintText("flange", c.flange);
    }
  });
}

}  // namespace selfcal::cli
