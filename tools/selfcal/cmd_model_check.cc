// `selfcal model-check FILE...`: reads robot model files strictly and reports what is wrong.
#include <iostream>

#include "protocols/model_file/model_file.h"
#include "tools/selfcal/cli_util.h"
#include "tools/selfcal/commands.h"

namespace selfcal::cli {

void RegisterModelCheck(CLI::App& app) {
  auto* command = app.add_subcommand(
      "model-check", "Read robot model files strictly; print joints and calibrated parameters");
  auto files = std::make_shared<std::vector<std::string>>();
  command->add_option("files", *files, "Robot model files (YAML)")
      ->required()
      ->check(kFileNotFolder);
  command->callback([files] {
    for (const auto& path : *files) {
      const auto file = ReadModelFile(path);
      if (!file) {
        exit_code = Fail(file.error().message);
        return;
      }
      const RobotModel& model = file->model;
      std::size_t calibrated = 0;
      for (bool flag : model.mask) calibrated += flag ? 1 : 0;
      std::cout << path << ": " << model.name << ", " << model.JointCount() << " joints, "
                << model.ParameterCount() << " parameters, " << calibrated << " calibrated ("
                << (file->mask_given ? "mask from file" : "paper's default mask") << ")\n";
    }
  });
}

}  // namespace selfcal::cli
