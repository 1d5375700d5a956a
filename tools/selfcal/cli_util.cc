#include "tools/selfcal/cli_util.h"

#include <filesystem>
#include <string>

namespace selfcal::cli {

const CLI::Validator kFileNotFolder(
    [](const std::string& input) -> std::string {
      std::error_code error;
      return std::filesystem::is_directory(input, error) ? input + " is a folder, not a file" : "";
    },
    // No name: the help keeps showing "TEXT=default", as before the check.
    "");

const CLI::Validator kOutputFile(
    [](const std::string& input) -> std::string {
      std::error_code error;
      if (std::filesystem::is_directory(input, error)) return input + " is a folder, not a file";
      const std::filesystem::path folder = std::filesystem::path(input).parent_path();
      if (folder.empty() || std::filesystem::is_directory(folder, error)) return "";
      return input + ": the folder " + folder.string() +
             (std::filesystem::exists(folder, error) ? " is not a folder" : " does not exist");
    },
    "");

CLI::Option* AddInputFile(CLI::App* command, const std::string& name, std::string& file,
                          const std::string& description) {
  return AddOptionalInputFile(command, name, file, description)->required();
}

CLI::Option* AddOptionalInputFile(CLI::App* command, const std::string& name, std::string& file,
                                  const std::string& description) {
  return command->add_option(name, file, description)->check(kFileNotFolder);
}

CLI::Option* AddOutputFile(CLI::App* command, const std::string& name, std::string& file,
                           const std::string& description) {
  return command->add_option(name, file, description)->check(kOutputFile);
}

CLI::Option* AddScenarioFile(CLI::App* command, std::string& scenario) {
  return AddInputFile(command, "scenario", scenario, "Scenario file (config/scenarios/*.yaml)");
}

}  // namespace selfcal::cli
