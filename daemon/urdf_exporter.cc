#include "daemon/urdf_exporter.h"

#ifdef SELFCAL_HAVE_URDF
#include "protocols/model_file/urdf.h"
#endif

namespace selfcal::daemon {

UrdfExporter DefaultUrdfExporter() {
#ifdef SELFCAL_HAVE_URDF
  return [](const RobotModel& model) -> Expected<std::string> { return FormatUrdf(model); };
#else
  return {};  // this tree has no URDF writer yet: models are installed as YAML only
#endif
}

}  // namespace selfcal::daemon
