// `selfcal import (--urdf FILE [--base-link L] [--tip-link L] | --dh FILE) --out MODEL.yaml`:
// converts a URDF chain or a standard DH table into an MCPC robot model file.
#include <spdlog/spdlog.h>

#include <memory>

#include "core/model/chain.h"
#include "protocols/model_file/dh_file.h"
#include "protocols/model_file/model_file.h"
#include "protocols/model_file/urdf.h"
#include "tools/selfcal/cli_util.h"
#include "tools/selfcal/commands.h"

namespace selfcal::cli {

void RegisterImport(CLI::App& app) {
  auto* command = app.add_subcommand(
      "import", "Convert a URDF chain or a standard DH table (YAML) into an MCPC robot model file");
  struct Options {
    std::string urdf, dh, out, name;
    UrdfImportOptions urdf_options;
  };
  auto options = std::make_shared<Options>();
  auto* urdf = AddOptionalInputFile(command, "--urdf", options->urdf, "URDF file");
  auto* dh =
      AddOptionalInputFile(command, "--dh", options->dh, "DH table (YAML, see docs/kinematics.md)");
  urdf->excludes(dh);
  command
      ->add_option("--base-link", options->urdf_options.base_link,
                   "URDF: first link of the chain (default: the root link)")
      ->needs(urdf);
  command
      ->add_option("--tip-link", options->urdf_options.tip_link,
                   "URDF: last link of the chain (default: the only leaf)")
      ->needs(urdf);
  command
      ->add_option("--max-acceleration", options->urdf_options.default_max_acceleration,
                   "URDF: acceleration limit for every joint (URDF has none)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber)
      ->needs(urdf);
  command->add_option("--name", options->name, "Robot name (default: the source's)");
  command->add_option("--out", options->out, "Robot model file to write (atomically)")->required();
  command->callback([options] {
    spdlog::info("import: urdf={} dh={} base_link={} tip_link={} out={}", options->urdf,
                 options->dh, options->urdf_options.base_link, options->urdf_options.tip_link,
                 options->out);
    if (options->urdf.empty() == options->dh.empty()) {
      exit_code = Fail("give one of --urdf and --dh");
      return;
    }
    Expected<McpcConversion> converted = Error{};
    if (!options->urdf.empty()) {
      converted = ReadUrdfFile(options->urdf, options->urdf_options);
    } else {
      const auto table = ReadDhFile(options->dh);
      if (!table) {
        exit_code = Fail(table.error().message);
        return;
      }
      converted = ChainToMcpc(DhToChain(*table));
      if (!converted) converted = Error{options->dh + ": " + converted.error().message};
    }
    if (!converted) {
      exit_code = Fail(converted.error().message);
      return;
    }
    for (const auto& note : converted->notes) spdlog::warn("{}", note);
    RobotModel& model = converted->model;
    if (!options->name.empty()) model.name = options->name;
    if (const Status written = WriteModelFile(options->out, model); !written) {
      exit_code = Fail(written.error().message);
      return;
    }
    spdlog::info("wrote {} ({} joints, {} parameters)", options->out, model.JointCount(),
                 model.ParameterCount());
  });
}

}  // namespace selfcal::cli
