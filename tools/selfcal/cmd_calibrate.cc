// `selfcal calibrate`: runs the engine on a recording, exactly as the daemon does
// (protocols/recording ReadRecording + core/calib Calibrate), judges the result with the daemon's
// gate (daemon/gate.h JudgeCalibration) and writes the result model file.
// Exit codes: 0 usable, that is what selfcald would install (converged, validated, better on the
// held-back scans); 1 bad input (no file written); 2 bad command line (no work done); 3 result
// written but not usable (the output says why).
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>
#include <utility>

#include "core/calib/calibrate.h"
#include "core/calib/parameter_limits.h"
#include "core/model/evaluation.h"
#include "daemon/config.h"
#include "daemon/engine.h"
#include "daemon/gate.h"
#include "daemon/remaster.h"
#include "protocols/model_file/model_file.h"
#include "protocols/model_file/sensor_config.h"
#include "protocols/recording/recording.h"
#include "tools/selfcal/cli_util.h"
#include "tools/selfcal/commands.h"
#include "tools/selfcal/pose_error_text.h"
#include "tools/selfcal/progress.h"

namespace selfcal::cli {

namespace {

struct CalibrateArguments {
  std::string robot, sensor, log, out, truth;
  std::string mode = "full";  // full (the robot file's mask) or remaster (RemasterMask)
  int scans = 0;
  int threads = 0;
  std::string solver = "fast";
  std::string search;               // empty = the --solver's name
  std::string cost;                 // empty = the engine's default
  std::string loss;                 // empty = the engine's default
  std::string normals;              // empty = the engine's default
  bool noise_correction = false;    // --noise-correction
  std::string step_measure;         // empty = the engine's default
  int acceleration = -1;            // < 0 = the engine's default
  double loss_width = 0;            // 0 = the engine's default
  std::string border;               // empty = the sensor layout's (CalibrationOptionsFromSensor)
  std::optional<double> latency_s;  // s; unset = the sensor file's
  bool elasticity = false;          // compliance per joint (docs/engine.md deviation 15)
  int estimate_latency = -1;        // latency_s is the start value (deviation 16); -1: the
                                    // sensor's default (sweeping sensors estimate it)
  std::string intrinsics;  // which intrinsics it calibrates (deviation 17); empty = the sensor's
  std::vector<double> intrinsics_uncertainty;  // scale, offset [m], focal; empty = the sensor's
  std::vector<double> link_masses;             // kg; empty = the robot file's gravity: block
  double sensor_mass = -1;                     // kg; < 0 = the robot file's
  int max_iterations = 0;                      // 0 = the engine's i_max
  int lm_iterations = 0;                       // 0 = the engine's lm_max_iterations
  int query_stride = 0;                        // 0 = the sensor file's
  int coarse_stride = 0;                       // 0 = the sensor file's
  double flying_pixel_angle = -1;              // deg; < 0 = the sensor file's (deviation 19)
  double link_radius = -1;  // m; < 0 = the robot file's links: block (deviation 20)
  double link_margin = -1;  // m; < 0 = the engine's
  bool allow_incomplete = false;
  bool no_validation = false;  // judge a recording without validation scans on the other rules
  std::string daemon_config;   // whose acceptance gate decides `usable`; empty = the defaults
};

// The engine's reports as progress: one stage per ICP iteration, its bar the convergence measure
// against epsilon (most runs stop there, long before i_max).
class CalibrationProgressView {
 public:
  CalibrationProgressView(Progress::Mode mode, const calib::CalibrationOptions& options)
      : progress_(mode),
        epsilon_(options.epsilon),
        step_name_(calib::StepMeasureLabel(options.step_measure)) {}
  void operator()(const calib::CalibrationProgress& report) {
    switch (report.stage) {
      case calib::CalibrationStage::kValidation:
        progress_.Update("validation", 0, "matching the held-back scans");
        return;
      case calib::CalibrationStage::kCovariance:
        progress_.Update("covariance", 1,
                         "after " + std::to_string(report.iteration) + " iterations");
        return;
      case calib::CalibrationStage::kIterationDone:
        if (first_delta_ == 0) first_delta_ = report.delta;
        last_delta_ = report.delta;
        last_matches_ = report.valid_matches;
        return;
      case calib::CalibrationStage::kMatching:
      case calib::CalibrationStage::kSolving:
        break;
    }
    progress_.Update(
        "iteration " + std::to_string(report.iteration),
        first_delta_ == 0 ? 0 : ConvergenceFraction(first_delta_, last_delta_, epsilon_),
        calib::StageName(report.stage) + LastStepText(report));
  }

 private:
  // The previous iteration's step against the stopping rule: the honest measure of how far
  // there is to go.
  std::string LastStepText(const calib::CalibrationProgress& report) const {
    if (report.iteration <= 1) return "";
    char text[160];
    std::snprintf(text, sizeof(text),
                  "; iteration %d: %s %.2e (stops at %.1e, at most %d iterations), %zu matches",
                  report.iteration - 1, step_name_, last_delta_, epsilon_, report.max_iterations,
                  last_matches_);
    return text;
  }
  Progress progress_;
  double epsilon_;
  const char* step_name_;
  double first_delta_ = 0, last_delta_ = 0;
  std::size_t last_matches_ = 0;
};

// `value` rounded to a whole number, never "-0".
double Whole(double value) { return std::round(value) + 0.0; }

// What changed against the --robot model (the installed one, on a robot), and what keeping it
// would cost, taking the result as the truth.
void PrintChange(const ModelChange& change) {
  std::printf("what changed against the --robot model: %s\n", change.Summary().c_str());
  std::printf("  keeping it: sensor position %.3f mm RMS, flange %.3f mm RMS, over %s\n",
              change.kept_installed.sensor.rms_position_m * 1e3,
              change.kept_installed.flange.rms_position_m * 1e3,
              SampleSetText(change.kept_installed.samples, change.kept_installed.seed).c_str());
}

// The covariance's predicted error, and the joint ranges where it is largest (one line).
void PrintPredicted(const calib::CalibrationResult& result) {
  const auto& predicted = result.predicted;
  std::printf(
      "predicted error (1 sigma, %s covariance over %zu scans), %s:\n"
      "  sensor position %.4f mm RMS, worst %.4f mm; orientation %.5f deg RMS, worst %.5f deg\n"
      "  flange position %.4f mm RMS, worst %.4f mm\n",
      result.jackknife_scans > 0 ? "jackknife" : "naive", result.jackknife_scans,
      SampleSetText(predicted.samples, predicted.seed).c_str(),
      predicted.sensor.rms_position_m * 1e3, predicted.sensor.max_position_m * 1e3,
      predicted.sensor.rms_orientation_rad * 180 / M_PI,
      predicted.sensor.max_orientation_rad * 180 / M_PI, predicted.flange.rms_position_m * 1e3,
      predicted.flange.max_position_m * 1e3);
  std::string regions;
  for (const auto& region : predicted.map.worst) {
    const auto& joint = predicted.map.joints[region.joint];
    const double unit = joint.prismatic ? 1e3 : 180 / M_PI;
    char text[96];
    std::snprintf(text, sizeof text, "%s%s in [%.0f, %.0f] %s %.4f mm", regions.empty() ? "" : ", ",
                  joint.joint.c_str(), Whole(region.lower * unit), Whole(region.upper * unit),
                  joint.prismatic ? "mm" : "deg", region.sensor_rms_position_m * 1e3);
    regions += text;
  }
  if (!regions.empty()) std::printf("  largest sensor position RMS: %s\n", regions.c_str());
  if (result.predicted_held.samples > 0)
    std::printf(
        "  of which what the calibration holds (intrinsics, compliance): sensor position %.4f mm "
        "RMS, worst %.4f mm\n",
        result.predicted_held.sensor.rms_position_m * 1e3,
        result.predicted_held.sensor.max_position_m * 1e3);
  std::printf("  (the naive covariance, every match independent: sensor position %.4f mm RMS)\n",
              result.predicted_naive.sensor.rms_position_m * 1e3);
}

// How far the validation scans' sensor origins move when each is registered onto the fit scans:
// the model's error where it was not fitted (core/calib/held_out_registration.h).
void PrintHeldOut(const calib::HeldOutRegistration& held_out) {
  if (held_out.scans.empty()) return;
  const auto worst =
      std::max_element(held_out.scans.begin(), held_out.scans.end(),
                       [](const auto& a, const auto& b) { return a.position_m < b.position_m; });
  std::printf(
      "held-out scans registered onto the fit scans: sensor origin moved %.4f mm RMS over %zu "
      "scans, worst %.4f mm (scan %d)\n",
      held_out.rms_position_m * 1e3, held_out.scans.size(), worst->position_m * 1e3,
      worst->scan_index);
}

// With --elasticity: each calibrated joint's compliance and its 1 sigma (docs/engine.md
// deviation 15), in urad/Nm.
void PrintCompliance(const calib::CalibrationResult& result) {
  std::string line;
  for (const calib::ParameterReport& parameter : result.parameters) {
    const auto dot = parameter.name.rfind(".compliance");
    if (dot == std::string::npos) continue;
    char text[96];
    std::snprintf(text, sizeof text, "%s%s %.3f +- %.3f", line.empty() ? "" : ", ",
                  parameter.name.substr(0, dot).c_str(), parameter.calibrated * 1e6,
                  parameter.std_dev * 1e6);
    line += text;
  }
  if (!line.empty()) std::printf("compliance (urad/Nm, 1 sigma): %s\n", line.c_str());
}

// With --estimate-latency: the sensor latency of each recording and its 1 sigma
// (docs/engine.md deviation 16), in ms.
void PrintLatency(const calib::CalibrationResult& result) {
  for (const calib::ParameterReport& parameter : result.parameters) {
    if (!parameter.name.ends_with(".latency")) continue;
    std::printf("%s: %.3f ms +- %.3f ms (1 sigma; started at %.3f ms)\n", parameter.name.c_str(),
                parameter.calibrated * 1e3, parameter.std_dev * 1e3, parameter.nominal * 1e3);
  }
}

// With --intrinsics: the correction of the sensor's intrinsics and its 1 sigma (docs/engine.md
// deviation 17): scales in percent, the offset in mm.
void PrintIntrinsics(const calib::CalibrationResult& result) {
  for (const calib::ParameterReport& parameter : result.parameters) {
    const std::string& name = parameter.name;
    if (!name.starts_with("sensor.depth_") && !name.starts_with("sensor.range_") &&
        name != "sensor.focal_scale")
      continue;
    const bool scale = name.ends_with("_scale");
    std::printf("%s: %+.4f %s +- %.4f %s (1 sigma; the correction applied to the measure)\n",
                name.c_str(), parameter.calibrated * (scale ? 100 : 1e3), scale ? "%" : "mm",
                parameter.std_dev * (scale ? 100 : 1e3), scale ? "%" : "mm");
  }
}

// "--cost must be paper, target or symmetric, not 'x'": an option's value that names no choice.
template <typename Enum, std::size_t N>
std::string NotOneOf(const std::string& option, const std::string& value,
                     const EnumNames<Enum, N>& names) {
  return option + " must be " + names.Listed() + ", not '" + value + "'";
}

int RunCalibrate(const CalibrateArguments& args) {
  if (args.mode != "full" && args.mode != "remaster") {
    return Fail("--mode must be full or remaster, not '" + args.mode + "'", program::kExitUsage);
  }
  const auto solver = calib::kSolverNames.Parse(args.solver);
  if (!solver) return Fail(NotOneOf("--solver", args.solver, calib::kSolverNames));
  // --solver alone picks the mode (search and solver together), as it always did.
  const std::string search_name = args.search.empty() ? args.solver : args.search;
  const auto search = calib::kSearchNames.Parse(search_name);
  if (!search) return Fail(NotOneOf("--search", search_name, calib::kSearchNames));
  const auto cost = calib::kCostNames.Parse(args.cost);
  if (!args.cost.empty() && !cost) return Fail(NotOneOf("--cost", args.cost, calib::kCostNames));
  const auto normals = calib::kNormalNames.Parse(args.normals);
  if (!args.normals.empty() && !normals) {
    return Fail(NotOneOf("--normals", args.normals, calib::kNormalNames));
  }
  const auto loss = calib::kLossNames.Parse(args.loss);
  if (!args.loss.empty() && !loss) return Fail(NotOneOf("--loss", args.loss, calib::kLossNames));
  const auto step_measure = calib::kStepMeasureNames.Parse(args.step_measure);
  if (!args.step_measure.empty() && !step_measure) {
    return Fail(NotOneOf("--step-measure", args.step_measure, calib::kStepMeasureNames));
  }
  if (!args.border.empty() && args.border != "off" && args.border != "exact" &&
      args.border != "surface") {
    return Fail("--border-rule must be off, exact or surface, not '" + args.border + "'");
  }
  if (args.scans < 0) return Fail("--scans must be >= 0");
  // A latency meant in milliseconds ("--latency 12") reads every joint state 12 s away from its
  // scan and fails later on joint-state gaps that do not name the option.
  if (args.latency_s && !calib::kLatencyLimit.allows(*args.latency_s)) {
    return Fail(
        fmt::format("--latency is in seconds and must lie {}, not {} (12 ms is --latency "
                    "0.012)",
                    calib::kLatencyLimit.requirement, *args.latency_s));
  }
  const auto robot = ReadModelFile(args.robot);
  if (!robot) return Fail(robot.error().message);
  // What the engine frees: the file's mask, or (remaster) only what the joints' zero offsets and
  // the sensor mount move. The result file keeps the file's mask for the next full calibration.
  RobotModel engine_model = robot->model;
  if (args.mode == "remaster") {
    auto start = daemon::RemasterStart(robot->model);
    if (!start) return Fail(args.robot + ": " + start.error().message);
    engine_model = std::move(*start);
  }
  const auto sensor = ReadSensorConfig(args.sensor);
  if (!sensor) return Fail(sensor.error().message);
  if (!args.link_masses.empty()) {
    if (args.link_masses.size() != engine_model.JointCount())
      return Fail("--link-masses has " + std::to_string(args.link_masses.size()) +
                  " entries, the robot has " + std::to_string(engine_model.JointCount()) +
                  " joints");
    for (double mass : args.link_masses) {
      if (!(mass > 0) || !std::isfinite(mass)) return Fail("--link-masses must be > 0 kg");
    }
    engine_model.gravity.link_masses = args.link_masses;
  }
  if (args.sensor_mass >= 0) {
    if (!std::isfinite(args.sensor_mass)) return Fail("--sensor-mass must be finite");
    engine_model.gravity.sensor_mass = args.sensor_mass;
  } else if ((args.elasticity || !engine_model.gravity.compliance_sd.empty()) &&
             engine_model.gravity.sensor_mass == 0) {
    engine_model.gravity.sensor_mass = sensor->mass;  // the sensor file's mass_kg, if any
  }
  if (args.link_radius >= 0) {
    if (!(args.link_radius <= RobotModel::kMaxLinkRadius))
      return Fail("--link-radius must be within 0 .. 0.5 m (0 = keep the points on the links)");
    engine_model.link_radius = args.link_radius;
  }
  if (args.elasticity && !engine_model.gravity.Present()) {
    return Fail(
        "--elasticity needs link masses: the robot file's gravity: block "
        "(docs/formats.md) or --link-masses");
  }
  std::optional<ModelFile> truth;
  if (!args.truth.empty()) {
    auto truth_file = ReadModelFile(args.truth);
    if (!truth_file) return Fail(truth_file.error().message);
    if (truth_file->model.JointCount() != robot->model.JointCount()) {
      return Fail(args.truth + ": " + std::to_string(truth_file->model.JointCount()) + " joints, " +
                  args.robot + " has " + std::to_string(robot->model.JointCount()));
    }
    truth = std::move(*truth_file);
  }

  recording::RecordingOptions recording_options;
  recording_options.latency_s = args.latency_s;
  recording_options.max_fit_scans = args.scans;
  calib::CalibrationOptions options = recording::CalibrationOptionsFromSensor(*sensor);
  options.search = *search;
  options.solver = *solver;
  options.threads = args.threads;
  // 0 keeps the sensor file's or the engine's value; IsValid() rejects the rest out of range.
  if (args.max_iterations != 0) options.i_max = args.max_iterations;
  if (args.lm_iterations != 0) options.lm_max_iterations = args.lm_iterations;
  if (args.query_stride != 0) options.query_stride = args.query_stride;
  if (args.coarse_stride != 0) options.coarse_stride = args.coarse_stride;
  if (args.flying_pixel_angle >= 0) options.flying_pixel_angle_deg = args.flying_pixel_angle;
  if (args.link_margin >= 0) options.link_margin_m = args.link_margin;
  if (cost) options.cost = *cost;
  if (normals) options.normals = *normals;
  if (args.noise_correction) options.ray_noise_correction = true;
  if (loss) options.loss = *loss;
  if (step_measure) options.step_measure = *step_measure;
  if (args.acceleration >= 0) options.acceleration = args.acceleration;
  if (args.loss_width != 0) options.loss_width = args.loss_width;
  if (!args.border.empty()) {
    options.reject_coverage_border = args.border != "off";
    options.surface_border = args.border == "surface";
  }
  options.elasticity = args.elasticity;
  if (args.estimate_latency >= 0) options.estimate_latency = args.estimate_latency == 1;
  if (args.estimate_latency < 0 && options.solver == calib::SolverKind::kReference)
    options.estimate_latency = false;  // Ceres runs the paper's chain: the latency as given
  recording_options.joint_timing = options.estimate_latency;
  if (!args.intrinsics.empty()) {
    if (std::string problem = options.ChooseIntrinsics(args.intrinsics); !problem.empty())
      return Fail("--intrinsics " + problem);
  } else if (options.solver == calib::SolverKind::kReference) {
    options.ChooseIntrinsics("none");  // Ceres runs the paper's chain: the sensor as given
  }
  if (!args.intrinsics_uncertainty.empty()) {
    options.intrinsic_scale_sd = args.intrinsics_uncertainty[0];
    options.intrinsic_offset_sd_m = args.intrinsics_uncertainty[1];
    options.intrinsic_focal_sd = args.intrinsics_uncertainty[2];
  }
  if (std::string problem; !options.IsValid(&problem)) return Fail("options: " + problem);
  std::size_t free_parameters = 0;
  for (bool free : engine_model.mask) free_parameters += free ? 1 : 0;
  spdlog::info(
      "calibrate: mode={} ({} parameters) robot={} sensor={} ({}) log={} out={} scans={} "
      "threads={} search={} solver={} latency_s={}",
      args.mode, free_parameters, args.robot, args.sensor, kSensorLayoutNames.Name(sensor->layout),
      args.log, args.out, args.scans == 0 ? std::string("all") : std::to_string(args.scans),
      args.threads == 0 ? std::string("all cores") : std::to_string(args.threads), search_name,
      args.solver, args.latency_s.value_or(sensor->latency_s));
  spdlog::info(
      "calibrate: n={} m={} g_min={} d_max={} f_min={} epsilon={} i_max={} lm_max_iterations={} "
      "query_stride={} coarse_stride={} flying_pixel_angle={} link_radius={} link_margin={} "
      "step_measure={} acceleration={} cost={} normals={} noise_correction={} loss={} "
      "loss_width={} border_rule={} elasticity={} estimate_latency={} intrinsics={} "
      "intrinsics_uncertainty={}/{}/{}",
      options.filter_n, options.filter_m, options.g_min, options.d_max, options.f_min,
      options.epsilon, options.i_max, options.lm_max_iterations, options.query_stride,
      options.coarse_stride, options.flying_pixel_angle_deg,
      engine_model.link_radius > 0 ? std::to_string(engine_model.link_radius) : "off",
      options.link_margin_m, calib::kStepMeasureNames.Name(options.step_measure),
      options.acceleration, calib::CostName(options.cost), calib::NormalName(options.normals),
      options.ray_noise_correction ? "on" : "off", calib::LossName(options.loss),
      options.loss_width,
      !options.reject_coverage_border ? "off" : (options.surface_border ? "surface" : "exact"),
      options.elasticity ? "on" : "off", options.estimate_latency ? "on" : "off",
      options.IntrinsicsName(), options.intrinsic_scale_sd, options.intrinsic_offset_sd_m,
      options.intrinsic_focal_sd);

  // Hashed before the long calibration: the result names the inputs as they were read.
  const auto provenance = recording::MakeProvenance(
      std::string("selfcal ") + SELFCAL_VERSION,
      {{"robot", args.robot}, {"sensor", args.sensor}, {"recording", args.log}});
  if (!provenance) return Fail(provenance.error().message);

  daemon::AcceptanceConfig acceptance;
  if (!args.daemon_config.empty()) {
    auto daemon_config = daemon::ReadDaemonConfig(args.daemon_config);
    if (!daemon_config) return Fail(daemon_config.error().message);
    acceptance = daemon_config->acceptance;
  }
  if (args.mode == "remaster") acceptance = daemon::RemasterAcceptance(acceptance);
  spdlog::info(
      "calibrate: acceptance gate of {}: max_predicted_error_m={} min_improvement={} "
      "noise_floor_m={} max_angle_change_rad={} max_translation_change_m={}{}",
      args.daemon_config.empty() ? std::string("selfcald's defaults") : args.daemon_config,
      acceptance.max_predicted_error, acceptance.min_improvement, acceptance.noise_floor,
      acceptance.max_angle_change, acceptance.max_translation_change,
      args.no_validation ? ", validation scans not required" : "");

  const auto load_start = std::chrono::steady_clock::now();
  recording_options.allow_incomplete = true;  // the command's own policy follows
  auto recording = recording::ReadRecording(args.log, robot->model, *sensor, recording_options);
  if (!recording) return Fail(recording.error().message);
  if (!recording->incomplete.empty()) {
    if (!args.allow_incomplete) {
      return Fail(recording->incomplete + " (--allow-incomplete calibrates with them)");
    }
    spdlog::warn("{}: using the complete scans only", recording->incomplete);
  }
  for (const std::string& warning : recording->warnings) {
    spdlog::warn("{}: {}", args.log, warning);
  }
  const std::vector<calib::Dataset>& datasets = recording->datasets;
  const auto fit_scans = static_cast<int>(std::count_if(
      datasets.begin(), datasets.end(), [](const calib::Dataset& d) { return !d.validation; }));
  if (args.scans > fit_scans) {
    spdlog::warn("--scans {}: the recording has {} fit scans; using all {}", args.scans, fit_scans,
                 fit_scans);
  }
  std::size_t points = 0;
  for (const auto& dataset : datasets) points += dataset.PointCount();
  spdlog::info(
      "calibrate: {} scans, {} points, loaded in {:.2f} s", datasets.size(), points,
      std::chrono::duration<double>(std::chrono::steady_clock::now() - load_start).count());

  calib::CalibrationResult result;
  {
    CalibrationProgressView view(Progress::ModeFor(), options);
    result = calib::Calibrate(std::move(recording->datasets), engine_model, options,
                              [&view](const calib::CalibrationProgress& p) { view(p); });
  }
  // What selfcald would install; RestoreRoundOff() inside makes the written model the same.
  daemon::CalibratedModel judged = daemon::ToCalibratedModel(
      result, engine_model, recording::FormatCalibrationYaml(result, &*provenance));
  const daemon::GateDecision decision = daemon::JudgeCalibration(
      acceptance, engine_model, judged,
      args.no_validation ? daemon::ValidationRule::kSkipped : daemon::ValidationRule::kRequired);
  judged.model.mask = robot->model.mask;
  std::string corrections;
  if (args.mode == "remaster") {
    // `--mode remaster`'s answer as a controller takes it (daemon/remaster.h, as selfcald's).
    const daemon::RemasterCorrections remaster =
        daemon::DescribeRemaster(robot->model, judged.model, "the --robot model");
    corrections = remaster.text;
    judged.calibration_yaml += remaster.yaml;
  }
  const Status written = WriteModelFile(args.out, judged.model, judged.calibration_yaml);
  if (!written) return Fail(written.error().message);

  std::printf("termination: %s (%s)\n", calib::TerminationName(result.termination),
              result.message.c_str());
  std::printf("iterations: %zu, runtime: %.2f s, search: %s, solver: %s, threads: %d",
              result.iterations.size(), result.runtime_s, calib::SearchName(result.search),
              calib::SolverName(result.solver), result.threads);
  if (options.acceleration > 0) {
    std::printf(", accelerated: %d (%d dropped)", result.accelerated, result.acceleration_dropped);
  }
  std::printf("\n");
  if (judged.model.link_radius > 0) {
    std::printf("points on the arm's own links (radius %.3f m + margin %.3f m): %zu removed\n",
                judged.model.link_radius, options.link_margin_m, result.points_on_links);
  }
  if (!result.iterations.empty()) {
    std::printf("valid matches (last iteration): %zu, point-to-plane RMS: %.4f mm -> %.4f mm\n",
                result.iterations.back().valid_matches,
                result.iterations.front().rms_before_m * 1e3,
                result.iterations.back().rms_after_m * 1e3);
  }
  if (result.validation.available) {
    std::printf("validation RMS: %.4f mm (%zu matches) -> %.4f mm (%zu matches)\n",
                result.validation.rms_before_m * 1e3, result.validation.matches_before,
                result.validation.rms_after_m * 1e3, result.validation.matches_after);
    PrintHeldOut(result.held_out);
  }
  for (const auto& entry : result.poorly_observable)
    std::printf("poorly observable: %s\n", entry.c_str());
  for (const auto& entry : result.unobservable) std::printf("unobservable: %s\n", entry.c_str());
  PrintCompliance(result);
  PrintLatency(result);
  PrintIntrinsics(result);
  if (!result.parameters.empty()) PrintPredicted(result);
  if (result.change_known) PrintChange(result.change);
  if (truth) {
    const PoseErrorStats before =
        SensorPoseError(truth->model, robot->model, kEvaluationSamples, kEvaluationSeed);
    const PoseErrorStats after =
        SensorPoseError(truth->model, judged.model, kEvaluationSamples, kEvaluationSeed);
    std::printf("sensor pose error vs truth, %s:\n  nominal    %s\n  calibrated %s\n",
                SampleSetText(kEvaluationSamples, kEvaluationSeed).c_str(),
                PoseErrorText(before).c_str(), PoseErrorText(after).c_str());
    if (result.predicted.sensor.rms_position_m > 0) {
      std::printf("  actual / predicted sensor position RMS: %.2f\n",
                  after.rms_position_m / result.predicted.sensor.rms_position_m);
    }
    if (result.held_out.rms_position_m > 0) {
      std::printf("  actual sensor position RMS / held-out scans' RMS: %.2f\n",
                  after.rms_position_m / result.held_out.rms_position_m);
    }
  }
  if (!corrections.empty()) std::fputs(corrections.c_str(), stdout);
  if (!recording->incomplete.empty()) std::printf("recording: %s\n", recording->incomplete.c_str());
  std::printf("usable: %s (%s), written to %s\n", decision.accepted ? "yes" : "no",
              decision.reason.c_str(), args.out.c_str());
  return decision.accepted ? 0 : 3;
}

}  // namespace

void RegisterCalibrate(CLI::App& app) {
  auto args = std::make_shared<CalibrateArguments>();
  auto* command = app.add_subcommand(
      "calibrate",
      "Calibrate the robot model from a recording (the paper's ICP bundle adjustment)");
  AddInputFile(command, "--robot", args->robot, "Nominal robot model file (YAML)");
  AddInputFile(command, "--sensor", args->sensor, "Sensor file (config/sensors/*.yaml, Table I)");
  AddInputFile(command, "--log", args->log, "Recording (LCM log, docs/recording.md)");
  AddOutputFile(command, "--out", args->out, "Result model file with a calibration: section")
      ->required();
  command->add_option(
      "--mode", args->mode,
      "full (default: every parameter the --robot file's mask calibrates) or "
      "remaster (only the joints' zero offsets and the sensor mount, for a motor or "
      "gearbox swap; also prints the offsets per joint in degrees, "
      "docs/quickstart.md)");
  command->add_option("--scans", args->scans,
                      "Use the first N fit scans (0 = all); validation scans always");
  command->add_option("--threads", args->threads,
                      "Threads (0 = all cores); results do not depend on it");
  command->add_option("--solver", args->solver,
                      "fast (default: own Levenberg-Marquardt) or reference (Ceres, one autodiff "
                      "residual per match, the paper's way, slow); also sets --search");
  command->add_option("--search", args->search,
                      "fast (pose knots, sensor-frame trees, bounded search) or reference (full "
                      "chain, base-frame trees, unbounded); default: as --solver");
  command->add_option("--cost", args->cost,
                      "Which normal a match's point-to-plane residual uses: paper (the query "
                      "point's), target (the matched point's) or symmetric (their sum; "
                      "docs/engine.md deviation 13)");
  command->add_option("--normals", args->normals,
                      "How a point's normal is estimated: neighbours (the paper's cross product "
                      "of its grid neighbours) or fit (a plane fitted along the view rays to the "
                      "filter window's points; docs/engine.md deviation 22); default: neighbours");
  command->add_flag("--noise-correction", args->noise_correction,
                    "With --intrinsics: take the part of the cost that the sensor file's noise "
                    "along the rays adds and the intrinsics change out of it, for scans taken at "
                    "rest (depth cameras; docs/engine.md deviation 23)");
  command->add_option("--loss", args->loss,
                      "How a match's residual enters the cost: squared (the paper's least "
                      "squares) or cauchy (robust: weighted by Cauchy's kernel at 2.3849 sigma "
                      "of the sensor file's noise; docs/engine.md deviation 14); default: "
                      "squared");
  command->add_option("--step-measure", args->step_measure,
                      "What epsilon bounds: sensor (how far an iteration's step moves the sensor "
                      "pose over the fit scans' poses) or parameters (|delta k|, the paper's); "
                      "default: sensor (docs/engine.md deviation 18)");
  command->add_option("--acceleration", args->acceleration,
                      "Anderson acceleration of the ICP loop: how many past steps it combines "
                      "(0 = the paper's plain loop); default: 5 (docs/engine.md deviation 18)");
  command->add_option("--loss-width", args->loss_width,
                      "The robust loss's scale in multiples of the match's noise sigma "
                      "(default 2.3849, Cauchy's 95 % efficiency constant)");
  command->add_option("--border-rule", args->border,
                      "Reject matches to the border of the other scan's coverage: off, exact "
                      "(docs/engine.md deviation 10) or surface (of the measured surface, "
                      "deviation 12); default: the sensor layout's");
  command->add_option("--latency", args->latency_s,
                      "Sensor latency relative to the joint states [s]; with --estimate-latency "
                      "its starting value. Default: the sensor file's latency: seconds, else 0");
  command->add_flag_callback(
      "--estimate-latency", [args] { args->estimate_latency = 1; },
      "Also calibrate the sensor latency, from the joint velocities of scans taken while moving "
      "(docs/engine.md deviation 16; needs --solver fast). Default: the sensor file's latency: "
      "estimate, else on for line scanners and LiDARs with the fast solver, off for depth "
      "cameras");
  command->add_flag_callback(
      "--no-estimate-latency", [args] { args->estimate_latency = 0; },
      "Take --latency as given (the paper's way)");
  command->add_option(
      "--intrinsics", args->intrinsics,
      "Also calibrate the sensor's intrinsics (docs/engine.md deviation 17; needs "
      "--solver fast): a '+'-list of scale (of the depth or range; not where every "
      "length of the arm is calibrated), offset (of the depth or range) and focal "
      "(a depth sensor's lateral scale), or auto (what the sensor and the mask can "
      "show), or none; default: the sensor file's calibrate_intrinsics, else offset for "
      "LiDARs with the fast solver, none for other sensors");
  command
      ->add_option("--intrinsics-uncertainty", args->intrinsics_uncertainty,
                   "SCALE,OFFSET,FOCAL: how far the intrinsics the calibration holds may be off "
                   "(1 sigma; relative, m, relative), added to the covariance (docs/engine.md "
                   "deviation 21); default: the sensor file's intrinsics_uncertainty, else 0,0,0")
      ->delimiter(',')
      ->expected(3);
  command->add_flag("--elasticity", args->elasticity,
                    "Also calibrate a compliance per joint, driven by the gravity torque of the "
                    "robot file's masses (docs/engine.md deviation 15; needs --solver fast)");
  command
      ->add_option("--link-masses", args->link_masses,
                   "Link masses [kg], one per joint, instead of the robot file's gravity: block")
      ->delimiter(',');
  command->add_option("--sensor-mass", args->sensor_mass,
                      "Mass of the sensor and its mount at the tool point [kg] (default: the robot "
                      "file's gravity: sensor_mass_kg, else the sensor file's mass_kg, else 0)");
  AddOptionalInputFile(
      command, "--truth", args->truth,
      "A simulation's truth.yaml: also print the sensor pose error before and after");
  command->add_option(
      "--max-iterations", args->max_iterations,
      "Stop after N ICP iterations (0 = i_max); for timing per iteration, see docs/performance.md");
  command->add_option(
      "--lm-iterations", args->lm_iterations,
      "Levenberg-Marquardt iterations per ICP iteration (0 = the engine's default)");
  command->add_option(
      "--query-stride", args->query_stride,
      "Match from every N-th grid row and column of each scan (0 = the sensor file's, "
      "1 = every point as the paper; docs/engine.md deviation 11)");
  command->add_option(
      "--coarse-stride", args->coarse_stride,
      "Coarse to fine: start the ICP loop matching from every N-th row and column and halve N "
      "each time it converges, down to --query-stride (0 = the sensor file's, 1 = off, the "
      "paper's loop; docs/engine.md deviation 24)");
  command->add_option(
      "--flying-pixel-angle", args->flying_pixel_angle,
      "Remove the points on depth steps (flying pixels, mixed returns) whose step to a neighbour "
      "lies within DEG of the view ray (0 = keep them, as the paper; default: the sensor "
      "file's; docs/engine.md deviation 19)");
  command->add_option(
      "--link-radius", args->link_radius,
      "Remove the points within M (plus --link-margin) of the arm's links, capsules along the "
      "model (0 = keep them, as the paper; default: the robot file's links: radius_m, else 0; "
      "docs/engine.md deviation 20)");
  command->add_option("--link-margin", args->link_margin,
                      "Margin [m] around the links for the model's error at the start "
                      "(default 0.03)");
  command->add_flag("--allow-incomplete", args->allow_incomplete,
                    "Calibrate a log that ends early (cut off, or still being written) with its "
                    "complete scans; without, such a log is an error");
  command->add_flag("--no-validation", args->no_validation,
                    "Judge a recording without validation scans on the other rules (selfcald "
                    "never installs such a result); without, it is not usable");
  AddOptionalInputFile(command, "--daemon-config", args->daemon_config,
                       "A selfcald configuration whose acceptance: gate decides 'usable' "
                       "(default: the gate's defaults, docs/daemon.md)");
  command->callback([args] { exit_code = RunCalibrate(*args); });
}

}  // namespace selfcal::cli
