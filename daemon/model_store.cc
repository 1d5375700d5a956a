#include "daemon/model_store.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "core/util/atomic_file.h"

namespace selfcal::daemon {
namespace fs = std::filesystem;
namespace {

Status SyncFolder(const std::string& folder) {
  const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return Error{folder + ": cannot open to fsync: " + std::strerror(errno)};
  const int rc = ::fsync(fd);
  ::close(fd);
  if (rc != 0) return Error{folder + ": fsync failed: " + std::strerror(errno)};
  return OkStatus();
}

}  // namespace

Expected<ModelStore> ModelStore::Open(const std::string& storage_folder,
                                      const std::string& nominal_path, UrdfExporter urdf_exporter) {
  ModelStore store(storage_folder + "/models", std::move(urdf_exporter));
  std::error_code error;
  fs::create_directories(store.folder_, error);
  if (error) return Error{store.folder_ + ": cannot create: " + error.message()};
  if (!store.CurrentId().empty()) {
    auto current = store.Current();
    if (!current) return Error{"the current model is unreadable: " + current.error().message};
    return store;
  }
  auto nominal = ReadModelFile(nominal_path);
  if (!nominal) return nominal.error();
  auto text = ReadFile(nominal_path);
  if (!text) return text.error();
  // The nominal file is installed byte for byte, so its comments and provenance survive.
  auto status = store.WriteModelFolder(kNominalModelId, *text, nominal->model);
  if (!status) return status.error();
  status = store.PointLink("current", kNominalModelId);
  if (!status) return status.error();
  return store;
}

std::string ModelStore::LinkTarget(const std::string& link) const {
  std::error_code error;
  const fs::path target = fs::read_symlink(folder_ + "/" + link, error);
  return error ? std::string() : target.filename().string();
}

std::string ModelStore::CurrentId() const { return LinkTarget("current"); }
std::string ModelStore::PreviousId() const { return LinkTarget("previous"); }

Expected<ModelFile> ModelStore::Current() const {
  if (CurrentId().empty()) return Error{folder_ + ": no current model"};
  return ReadModelFile(CurrentPath());
}

Status ModelStore::WriteModelFolder(const std::string& id, const std::string& yaml_text,
                                    const RobotModel& model) {
  const std::string folder = folder_ + "/" + id;
  std::error_code error;
  fs::create_directories(folder, error);
  if (error) return Error{folder + ": cannot create: " + error.message()};
  if (urdf_exporter_) {
    auto urdf = urdf_exporter_(model);
    if (!urdf) return Error{"URDF export of model " + id + ": " + urdf.error().message};
    auto status = WriteFileAtomically(folder + "/model.urdf", *urdf);
    if (!status) return status;
  }
  // model.yaml last: a folder with a model.yaml is complete.
  auto status = WriteFileAtomically(folder + "/model.yaml", yaml_text);
  if (!status) return status;
  return SyncFolder(folder_);
}

Status ModelStore::PointLink(const std::string& link, const std::string& id) {
  const std::string path = folder_ + "/" + link;
  const std::string temporary = path + ".new";
  ::unlink(temporary.c_str());
  if (::symlink(id.c_str(), temporary.c_str()) != 0) {
    return Error{temporary + ": cannot create the link: " + std::strerror(errno)};
  }
  if (::rename(temporary.c_str(), path.c_str()) != 0) {
    const int saved = errno;
    ::unlink(temporary.c_str());
    return Error{path + ": cannot replace the link: " + std::strerror(saved)};
  }
  return SyncFolder(folder_);
}

Status ModelStore::Install(const std::string& id, const RobotModel& model,
                           const std::string& calibration_yaml) {
  if (id.empty() || id == "current" || id == "previous" || id.find('/') != std::string::npos) {
    return Error{"invalid model id '" + id + "'"};
  }
  auto status = InstallFolder(id, model, calibration_yaml);
  // A failed install (a full disk) leaves no half-written folder behind.
  if (!status) (void)DiscardUninstalled(id);
  return status;
}

Status ModelStore::InstallFolder(const std::string& id, const RobotModel& model,
                                 const std::string& calibration_yaml) {
  auto status = WriteModelFolder(id, FormatModelFile(model, calibration_yaml), model);
  if (!status) return status;
  // A check that what we wrote reads back as the model we meant (strict reader).
  auto back = ReadModelFile(ModelPath(id));
  if (!back) return Error{"the new model does not read back: " + back.error().message};
  const std::string old_current = CurrentId();
  if (!old_current.empty()) {
    // A crash between these two renames leaves previous == current: still a valid state.
    status = PointLink("previous", old_current);
    if (!status) return status;
  }
  return PointLink("current", id);
}

Status ModelStore::Rollback() {
  const std::string previous = PreviousId();
  const std::string current = CurrentId();
  if (previous.empty() || previous == current) return Error{"no previous model to roll back to"};
  auto model = ReadModelFile(ModelPath(previous));
  if (!model) return Error{"the previous model is unreadable: " + model.error().message};
  auto status = PointLink("current", previous);
  if (!status) return status;
  return PointLink("previous", current);
}

Status ModelStore::DiscardUninstalled(const std::string& id) {
  if (id.empty() || id == CurrentId() || id == PreviousId()) return OkStatus();
  if (id == "current" || id == "previous" || id.find('/') != std::string::npos) {
    return Error{"invalid model id '" + id + "'"};
  }
  const std::string folder = folder_ + "/" + id;
  std::error_code error;
  if (!fs::exists(folder, error)) return OkStatus();
  fs::remove_all(folder, error);
  if (error) return Error{folder + ": cannot remove: " + error.message()};
  return SyncFolder(folder_);
}

}  // namespace selfcal::daemon
