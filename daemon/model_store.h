// The installed robot models: storage/models/<id>/{model.yaml, model.urdf}, with two symbolic
// links `current` and `previous` that are swapped atomically (symlink + rename + fsync of the
// folder). A crash leaves `current` on the old or the new model, never on a half-written one.
#pragma once

#include <functional>
#include <string>

#include "core/model/robot_model.h"
#include "core/util/expected.h"
#include "protocols/model_file/model_file.h"

namespace selfcal::daemon {

inline constexpr const char* kNominalModelId = "nominal";

// Turns a model into URDF text (protocols/model_file/urdf.h once it exists).
using UrdfExporter = std::function<Expected<std::string>(const RobotModel&)>;

class ModelStore {
 public:
  // Opens storage/models; when there is no current model yet, installs `nominal_path` as "nominal".
  static Expected<ModelStore> Open(const std::string& storage_folder,
                                   const std::string& nominal_path, UrdfExporter urdf_exporter);

  std::string CurrentId() const;   // empty when none
  std::string PreviousId() const;  // empty when none
  std::string CurrentPath() const { return folder_ + "/current/model.yaml"; }
  // The same path without opening the store (which would install the nominal model).
  static std::string CurrentPathIn(const std::string& storage_folder) {
    return storage_folder + "/models/current/model.yaml";
  }
  std::string ModelPath(const std::string& id) const { return folder_ + "/" + id + "/model.yaml"; }
  Expected<ModelFile> Current() const;

  // Writes models/<id>/ completely and durably, then previous := current, current := id.
  Status Install(const std::string& id, const RobotModel& model,
                 const std::string& calibration_yaml);
  // current := previous, previous := the model that was current. Error when there is no previous.
  Status Rollback();
  // Removes models/<id>/ when neither link points at it: what an install interrupted by a crash
  // left (a model.urdf, a model.yaml.tmp.<pid>, or a complete model never made current).
  Status DiscardUninstalled(const std::string& id);

 private:
  ModelStore(std::string folder, UrdfExporter exporter)
      : folder_(std::move(folder)), urdf_exporter_(std::move(exporter)) {}
  Status InstallFolder(const std::string& id, const RobotModel& model,
                       const std::string& calibration_yaml);
  Status WriteModelFolder(const std::string& id, const std::string& yaml_text,
                          const RobotModel& model);
  Status PointLink(const std::string& link, const std::string& id);
  std::string LinkTarget(const std::string& link) const;
  std::string folder_;
  UrdfExporter urdf_exporter_;
};

}  // namespace selfcal::daemon
