#include "daemon/installation_check.h"

#include <unistd.h>

#include <filesystem>

#include "daemon/auth.h"
#include "daemon/model_store.h"
#include "daemon/plan.h"
#include "protocols/model_file/model_file.h"
#include "protocols/model_file/sensor_config.h"

namespace selfcal::daemon {
namespace {

namespace fs = std::filesystem;

// The storage folder must be writable, or creatable: its nearest existing parent writable.
Expected<std::string> CheckStorage(const std::string& folder) {
  fs::path existing = fs::absolute(folder);
  while (!fs::exists(existing) && existing.has_parent_path() && existing != existing.parent_path())
    existing = existing.parent_path();
  if (!fs::is_directory(existing)) return Error{existing.string() + ": not a folder"};
  if (::access(existing.c_str(), W_OK | X_OK) != 0) {
    return Error{existing.string() + ": not writable by this user (storage " + folder + ")"};
  }
  if (existing == fs::absolute(folder)) return "storage " + folder + ": writable";
  return "storage " + folder + ": does not exist yet; " + existing.string() +
         " is writable, the daemon will create it";
}

}  // namespace

Expected<std::string> CheckInstallation(const DaemonConfig& config) {
  std::string report;
  auto key = auth::ReadKeyFile(config.key_file, /*require_private=*/true);
  if (!key) return key.error();
  report += "key " + config.key_file + ": readable, private\n";
  auto sensor = ReadSensorConfig(config.sensor);
  if (!sensor) return sensor.error();
  report += "sensor " + config.sensor + ": " + sensor->name + "\n";
  // The model the daemon would start from: the installed one, else the configured nominal model.
  const std::string installed = ModelStore::CurrentPathIn(config.storage.folder);
  const std::string model_path = fs::exists(installed) ? installed : config.robot_model;
  auto model = ReadModelFile(model_path);
  if (!model) return model.error();
  report += "model " + model_path + ": " + model->model.name + "\n";
  for (const auto& [name, path] : config.plans) {
    auto plan = ReadScanPlan(path);
    if (!plan) return plan.error();
    const std::string problem = CheckPlan(*plan, model->model, config.checks.limit_margin);
    if (!problem.empty()) return Error{path + ": " + problem};
    report += "plan " + name + " (" + path + "): " + std::to_string(plan->scans.size()) +
              " scans within the limits\n";
  }
  auto storage = CheckStorage(config.storage.folder);
  if (!storage) return storage.error();
  return report + *storage + "\n";
}

}  // namespace selfcal::daemon
