// `selfcal model-check FILE...`: reads robot model files strictly and reports what is wrong.
#include <fmt/format.h>

#include <cmath>
#include <iostream>
#include <string>
#include <vector>

#include "protocols/model_file/model_file.h"
#include "tools/selfcal/cli_util.h"
#include "tools/selfcal/commands.h"

namespace selfcal::cli {

namespace {

void PrintModel(const std::string& path, const ModelFile& file) {
  const RobotModel& model = file.model;
  std::vector<std::string> calibrated;
  for (std::size_t i = 0; i < model.mask.size(); ++i) {
    if (model.mask[i]) calibrated.push_back(ParameterName(model, i));
  }
  std::cout << path << ": " << model.name << ", " << model.JointCount() << " joints, "
            << model.ParameterCount() << " parameters, " << calibrated.size() << " calibrated ("
            << (file.mask_given ? "mask from file" : "paper's default mask") << ")\n";
  for (const JointSpec& joint : model.joints) {
    const bool revolute = joint.type == JointType::kRevolute;
    const double scale = revolute ? 180.0 / M_PI : 1e3;
    std::cout << fmt::format("  joint {}: {}, {:.1f} .. {:.1f} {}\n", joint.name,
                             revolute ? "revolute" : "prismatic", joint.lower * scale,
                             joint.upper * scale, revolute ? "deg" : "mm");
  }
  std::cout << "  calibrated:";
  for (const std::string& name : calibrated) std::cout << " " << name;
  std::cout << "\n";
}

}  // namespace

void RegisterModelCheck(CLI::App& app) {
  auto* command = app.add_subcommand(
      "model-check", "Read robot model files strictly; print joints and calibrated parameters");
  auto files = std::make_shared<std::vector<std::string>>();
  command->add_option("files", *files, "Robot model files (YAML)")
      ->required()
      ->check(kFileNotFolder);
  command->callback([files] {
    // Every file is checked, so that one run names every bad file of a folder.
    for (const auto& path : *files) {
      const auto file = ReadModelFile(path);
      if (!file) {
        exit_code = Fail(file.error().message);
        continue;
      }
      PrintModel(path, *file);
    }
  });
}

}  // namespace selfcal::cli
