// selfcal-hokuyo's configuration: a YAML file (strict: unknown keys are errors naming file and
// key) and command-line flags on top. See config/drivers/hokuyo.yaml for every key with its
// default.
#pragma once

#include <string>

#include "core/util/expected.h"
#include "drivers/hokuyo/driver.h"

namespace selfcal::hokuyo {

struct ProcessConfig {
  HokuyoConfig driver;
  std::string channel;  // default channels::kRangeScan
  std::string lcm_url;  // "" = LCM's default (LCM_DEFAULT_URL or udpm)
};

ProcessConfig DefaultProcessConfig();
// Reads `path` over `config` (keys absent from the file keep their value).
Status ReadProcessConfig(const std::string& path, ProcessConfig& config);
// "MD" / "ME".
Expected<scip::ScanType> ParseScanType(const std::string& name);

}  // namespace selfcal::hokuyo
