#include "daemon/urdf_exporter.h"

#include "protocols/model_file/urdf.h"

namespace selfcal::daemon {

UrdfExporter DefaultUrdfExporter() {
  return [](const RobotModel& model) -> Expected<std::string> { return FormatUrdf(model); };
}

}  // namespace selfcal::daemon
