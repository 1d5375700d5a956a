// `selfcal export --robot MODEL.yaml [--urdf OUT.urdf] [--ros2-control OUT.yaml --nominal N.yaml]
// [--ply OUT.ply --log REC --sensor S]`: the model as URDF joint origins, its joint zero offsets
// against the nominal as a ROS 2 parameter file, and the recording's scans fused with it as PLY.
// Every file is written atomically.
#include <spdlog/spdlog.h>

#include <memory>

#include "core/model/evaluation.h"
#include "core/model/joint_offsets.h"
#include "protocols/model_file/model_file.h"
#include "protocols/model_file/ply.h"
#include "protocols/model_file/ros2_control_offsets.h"
#include "protocols/model_file/sensor_config.h"
#include "protocols/model_file/urdf.h"
#include "protocols/recording/recording.h"
#include "protocols/report/fused_cloud.h"
#include "tools/selfcal/cli_util.h"
#include "tools/selfcal/commands.h"

namespace selfcal::cli {
namespace {

struct ExportOptions {
  std::string robot, urdf;
  std::string ros2_control, nominal;
  std::string ply, log, sensor, scans = "all";
  std::size_t max_points = 0;
};

Status ExportRos2Control(const ExportOptions& options, const RobotModel& model) {
  const auto nominal = ReadModelFile(options.nominal);
  if (!nominal) return nominal.error();
  if (const std::string problem = CheckComparable(nominal->model, model); !problem.empty()) {
    return Error{options.nominal + " and " + options.robot + ": " + problem};
  }
  const JointOffsetFit fit = FitJointOffsets(nominal->model, model);
  if (auto written = WriteRos2ControlOffsetsFile(options.ros2_control, model, fit, options.robot);
      !written) {
    return written;
  }
  spdlog::info("wrote {} (offsets of {} joints; {:.3f} mm RMS unexplained by offsets and mount)",
               options.ros2_control, model.JointCount(), fit.rms_position_m * 1e3);
  return OkStatus();
}

Status ExportPly(const ExportOptions& options, const RobotModel& model) {
  const auto sensor = ReadSensorConfig(options.sensor);
  if (!sensor) return sensor.error();
  const auto datasets = recording::LoadRecording(options.log, model, *sensor);
  if (!datasets) return datasets.error();
  const report::ScanSelection selection = options.scans == "validation"
                                              ? report::ScanSelection::kValidation
                                          : options.scans == "fit" ? report::ScanSelection::kFit
                                                                   : report::ScanSelection::kAll;
  const auto fused = report::FuseScans(*datasets, model, selection, options.max_points);
  const std::string comment =
      options.scans + " scans of " + options.log + " fused with " + options.robot + " (selfcal)";
  if (auto written = WritePlyFile(options.ply, report::ToPlyPoints(fused), comment); !written) {
    return written;
  }
  spdlog::info("wrote {} ({} points)", options.ply, fused.size());
  return OkStatus();
}

int RunExport(const ExportOptions& options) {
  if (options.urdf.empty() && options.ros2_control.empty() && options.ply.empty()) {
    return Fail("nothing to export: give --urdf, --ros2-control or --ply", program::kExitUsage);
  }
  spdlog::info("export: robot={} urdf={} ros2_control={} ply={}", options.robot, options.urdf,
               options.ros2_control, options.ply);
  const auto file = ReadModelFile(options.robot);
  if (!file) return Fail(file.error().message);
  if (!options.urdf.empty()) {
    if (const Status written = WriteUrdfFile(options.urdf, file->model); !written) {
      return Fail(written.error().message);
    }
    spdlog::info("wrote {} ({} joints)", options.urdf, file->model.JointCount());
  }
  if (!options.ros2_control.empty()) {
    if (const Status done = ExportRos2Control(options, file->model); !done) {
      return Fail(done.error().message);
    }
  }
  if (!options.ply.empty()) {
    if (const Status done = ExportPly(options, file->model); !done) {
      return Fail(done.error().message);
    }
  }
  return 0;
}

}  // namespace

void RegisterExport(CLI::App& app) {
  auto* command = app.add_subcommand(
      "export",
      "Write a robot model as URDF, its joint zero offsets as a ROS 2 parameter file, or a "
      "recording's scans fused with it as PLY");
  auto options = std::make_shared<ExportOptions>();
  AddInputFile(command, "--robot", options->robot, "Robot model file (YAML), e.g. a result");
  command->add_option("--urdf", options->urdf, "URDF file to write");
  auto* ros2 = AddOutputFile(command, "--ros2-control", options->ros2_control,
                             "ROS 2 parameter file of joint zero offsets against --nominal");
  AddOptionalInputFile(command, "--nominal", options->nominal,
                       "The nominal model the offsets are against");
  ros2->needs("--nominal");
  auto* ply = AddOutputFile(command, "--ply", options->ply,
                            "PLY file of the recording's scans fused with the model");
  AddOptionalInputFile(command, "--log", options->log, "Recording (LCM log) for --ply");
  AddOptionalInputFile(command, "--sensor", options->sensor, "Sensor file for --ply");
  command->add_option("--scans", options->scans, "Scans for --ply: all, fit or validation")
      ->check(CLI::IsMember({"all", "fit", "validation"}));
  command->add_option("--max-points", options->max_points,
                      "At most this many points in the PLY, every n-th kept (0 = all)");
  ply->needs("--log");
  ply->needs("--sensor");
  command->callback([options] { exit_code = RunExport(*options); });
}

}  // namespace selfcal::cli
