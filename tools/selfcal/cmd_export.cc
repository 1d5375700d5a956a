// `selfcal export --robot MODEL.yaml --urdf OUT.urdf`: the MCPC model as URDF joint origins.
#include <spdlog/spdlog.h>

#include <memory>

#include "protocols/model_file/model_file.h"
#include "protocols/model_file/urdf.h"
#include "tools/selfcal/cli_util.h"
#include "tools/selfcal/commands.h"

namespace selfcal::cli {

void RegisterExport(CLI::App& app) {
  auto* command = app.add_subcommand(
      "export",
      "Write a robot model as URDF (one joint per MCPC joint, origins = MCPC transforms)");
  struct Options {
    std::string robot;
    std::string urdf;
  };
  auto options = std::make_shared<Options>();
  command->add_option("--robot", options->robot, "Robot model file (YAML)")
      ->required()
      ->check(kFileNotFolder);
  command->add_option("--urdf", options->urdf, "URDF file to write (atomically)")->required();
  command->callback([options] {
    spdlog::info("export: robot={} urdf={}", options->robot, options->urdf);
    const auto file = ReadModelFile(options->robot);
    if (!file) {
      exit_code = Fail(file.error().message);
      return;
    }
    if (const Status written = WriteUrdfFile(options->urdf, file->model); !written) {
      exit_code = Fail(written.error().message);
      return;
    }
    spdlog::info("wrote {} ({} joints)", options->urdf, file->model.JointCount());
  });
}

}  // namespace selfcal::cli
