#include "daemon/urdf_exporter.h"

namespace selfcal::daemon {

UrdfExporter DefaultUrdfExporter() {
  // protocols/model_file/urdf.* has not landed yet: models are installed as YAML only.
  return {};
}

}  // namespace selfcal::daemon
