// `selfcal report RESULT.yaml --log RECORDING [--out FILE]`: the session report (protocols/report)
// of a result file of `selfcal calibrate`, judged by selfcald's acceptance gate (daemon/gate.h).
// The old model and the sensor file are the result's provenance inputs unless given.
#include <spdlog/spdlog.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <memory>

#include "daemon/config.h"
#include "daemon/engine.h"
#include "daemon/gate.h"
#include "daemon/gate_rules.h"
#include "daemon/remaster.h"
#include "protocols/model_file/model_file.h"
#include "protocols/model_file/sensor_config.h"
#include "protocols/report/report.h"
#include "tools/selfcal/cli_util.h"
#include "tools/selfcal/commands.h"

namespace selfcal::cli {
namespace {

struct ReportArguments {
  std::string result, log, out, robot, sensor, daemon_config;
  std::size_t max_points = report::ReportOptions{}.max_points_per_model;
};

// The path of the provenance input with `role`, as `selfcal calibrate` recorded it.
std::string InputPath(const YAML::Node& calibration, const std::string& role) {
  for (const YAML::Node& input : calibration["inputs"]) {
    if (input["role"] && input["role"].as<std::string>() == role) {
      return input["path"].as<std::string>("");
    }
  }
  return {};
}

// The result as the daemon judged it, from what the result file holds of ToCalibratedModel's
// fields: usable only when the engine said so and it converged, the validation evidence, the
// predicted sensor error and the unobservable parameters.
daemon::CalibratedModel Judged(const ModelFile& result, const YAML::Node& c) {
  daemon::CalibratedModel judged;
  judged.model = result.model;
  judged.usable = c["usable"].as<bool>(false) && c["converged"].as<bool>(false);
  judged.message = c["termination"].as<std::string>("") + ": " + c["message"].as<std::string>("");
  if (c["validation"]["available"].as<bool>(false)) {
    judged.validation_rms_before = c["validation"]["rms_before_m"].as<double>(-1);
    judged.validation_rms_after = c["validation"]["rms_after_m"].as<double>(-1);
    judged.validation_matches_before = c["validation"]["matches_before"].as<std::size_t>(0);
    judged.validation_matches_after = c["validation"]["matches_after"].as<std::size_t>(0);
    if (const YAML::Node held_out = c["validation"]["held_out_registration"];
        held_out && held_out["scans"].size() > 0) {
      judged.held_out_offset = held_out["rms_position_m"].as<double>(-1);
      judged.held_out_worst_offset = held_out["worst_position_m"].as<double>(-1);
    }
  }
  if (const YAML::Node sensor = c["predicted_error"]["sensor"]; sensor) {
    judged.predicted_error = sensor["rms_position_m"].as<double>(-1);
    judged.predicted_worst_error = sensor["max_position_m"].as<double>(-1);
  }
  if (const YAML::Node held = c["predicted_error"]["sensor_from_held"]; held)
    judged.predicted_held_error = held["rms_position_m"].as<double>(-1);
  for (const YAML::Node& entry : c["unobservable"]) {
    judged.unobservable.push_back(entry.as<std::string>());
  }
  return judged;
}

// The gate's decision as selfcald's or `selfcal calibrate`'s was: against the model the engine
// started from, so a remastering's result is judged against the remastering's mask
// (daemon/remaster.h JudgedAgainst), not the --robot file's, and with the remastering's rules.
Expected<report::GateSummary> Gate(const ReportArguments& args, const RobotModel& before,
                                   const std::string& calibration_yaml,
                                   daemon::CalibratedModel& judged) {
  const auto against = daemon::JudgedAgainst(before, calibration_yaml);
  if (!against) return Error{args.result + ": " + against.error().message};
  daemon::AcceptanceConfig acceptance;
  if (!args.daemon_config.empty()) {
    auto config = daemon::ReadDaemonConfig(args.daemon_config);
    if (!config) return config.error();
    acceptance = config->acceptance;
  }
  if (*daemon::IsRemastering(calibration_yaml)) {  // readable: JudgedAgainst read it
    acceptance = daemon::RemasterAcceptance(acceptance);
  }
  const daemon::GateDecision decision = daemon::JudgeCalibration(acceptance, *against, judged);
  return report::GateSummary{
      decision.accepted, decision.reason,
      args.daemon_config.empty() ? "selfcald's defaults" : args.daemon_config,
      daemon::DescribeGateRules(acceptance, *against, judged)};
}

int RunReport(ReportArguments args) {
  const auto result = ReadModelFile(args.result);
  if (!result) return Fail(result.error().message);
  if (result->calibration_yaml.empty()) return Fail(args.result + ": no calibration: section");
  const YAML::Node calibration = YAML::Load(result->calibration_yaml);
  if (args.robot.empty()) args.robot = InputPath(calibration, "robot");
  if (args.sensor.empty()) args.sensor = InputPath(calibration, "sensor");
  if (args.robot.empty() || args.sensor.empty()) {
    return Fail(args.result +
                ": its provenance names no robot or sensor file; give --robot and "
                "--sensor");
  }
  if (args.out.empty()) args.out = std::filesystem::path(args.result).replace_extension(".html");
  if (args.daemon_config.size() > 0 && !daemon::ReadDaemonConfig(args.daemon_config)) {
    return Fail(daemon::ReadDaemonConfig(args.daemon_config).error().message);
  }
  const auto before = ReadModelFile(args.robot);
  if (!before) return Fail(before.error().message);
  const auto sensor = ReadSensorConfig(args.sensor);
  if (!sensor) return Fail(sensor.error().message);

  report::ReportInput input;
  input.title = args.result;
  input.software = std::string("selfcal ") + SELFCAL_VERSION;
  input.before_name = args.robot;
  input.after_name = args.result;
  input.before = before->model;
  input.calibration_yaml = result->calibration_yaml;
  if (auto loaded = report::LoadRecordingInto(input, args.log, *sensor, {}); !loaded) {
    return Fail(loaded.error().message);
  }
  daemon::CalibratedModel judged = Judged(*result, calibration);
  auto gate = Gate(args, before->model, result->calibration_yaml, judged);
  if (!gate) return Fail(gate.error().message);
  input.gate = std::move(*gate);
  input.after = judged.model;
  input.rollback = "selfcal report only reads: nothing was installed. The old model is " +
                   args.robot +
                   ". On a robot whose selfcald installed this result, `selfcal "
                   "rollback` (a signed request) makes the model that was current before it "
                   "current again (models/previous -> models/current, docs/daemon.md).";
  report::ReportOptions options;
  options.max_points_per_model = args.max_points;
  if (auto written = report::WriteReport(args.out, input, options); !written) {
    return Fail(written.error().message);
  }
  spdlog::info("wrote {} ({} bytes)", args.out, std::filesystem::file_size(args.out));
  return 0;
}

}  // namespace

void RegisterReport(CLI::App& app) {
  auto args = std::make_shared<ReportArguments>();
  auto* command = app.add_subcommand(
      "report", "Write a calibration's report: one HTML file that opens without network");
  AddInputFile(command, "result", args->result, "Result model file of selfcal calibrate");
  AddInputFile(command, "--log", args->log, "The recording the result was calibrated from");
  AddOutputFile(command, "--out", args->out, "HTML file to write (default: RESULT with .html)");
  AddOptionalInputFile(command, "--robot", args->robot,
                       "The old model (default: the result's provenance)");
  AddOptionalInputFile(command, "--sensor", args->sensor,
                       "Sensor file (default: the result's provenance)");
  AddOptionalInputFile(command, "--daemon-config", args->daemon_config,
                       "Whose acceptance gate decides (default: selfcald's defaults)");
  command->add_option("--max-points", args->max_points,
                      "Points of the validation scans per model in the 3D view (0 = all)");
  command->callback([args] { exit_code = RunReport(*args); });
}

}  // namespace selfcal::cli
