#include "drivers/hokuyo/config.h"

#include "protocols/lcm/channels.h"
#include "protocols/model_file/yaml_reader.h"

namespace selfcal::hokuyo {

ProcessConfig DefaultProcessConfig() {
  ProcessConfig config;
  config.channel = channels::kRangeScan;
  return config;
}

Expected<scip::ScanType> ParseScanType(const std::string& name) {
  if (name == "MD") return scip::ScanType::kMD;
  if (name == "ME") return scip::ScanType::kME;
  return Error{"scan type '" + name + "' is not MD or ME"};
}

Status ReadProcessConfig(const std::string& path, ProcessConfig& config) {
  auto result = yaml::ReadDocumentFile<Ok>(path, [&](yaml::StrictMap& map) -> Ok {
    HokuyoConfig& d = config.driver;
    d.device = map.Optional<std::string>("device", d.device);
    d.host = map.Optional<std::string>("host", d.host);
    d.port = map.Optional<int>("port", d.port);
    d.usb = map.Optional<bool>("usb", d.usb);
    d.baud = map.Optional<int>("baud", d.baud);
    d.target_baud = map.Optional<int>("target_baud", d.target_baud);
    if (map.Has("scan_type")) {
      auto type = ParseScanType(map.Required<std::string>("scan_type"));
      if (!type) map.Fail("scan_type", "is not MD or ME");
      d.scan_type = *type;
    }
    d.start_step = map.Optional<int>("start_step", d.start_step);
    d.end_step = map.Optional<int>("end_step", d.end_step);
    d.cluster = map.Optional<int>("cluster", d.cluster);
    d.skip = map.Optional<int>("skip", d.skip);
    d.sync_exchanges = map.Optional<int>("sync_exchanges", d.sync_exchanges);
    d.sync_interval_s = map.Optional<double>("sync_interval_s", d.sync_interval_s);
    d.reply_timeout_s = map.Optional<double>("reply_timeout_s", d.reply_timeout_s);
    d.stall_timeout_s = map.Optional<double>("stall_timeout_s", d.stall_timeout_s);
    d.backoff_initial_s = map.Optional<double>("backoff_initial_s", d.backoff_initial_s);
    d.backoff_max_s = map.Optional<double>("backoff_max_s", d.backoff_max_s);
    config.channel = map.Optional<std::string>("channel", config.channel);
    config.lcm_url = map.Optional<std::string>("lcm_url", config.lcm_url);
    return Ok{};
  });
  if (!result) return result.error();
  return OkStatus();
}

}  // namespace selfcal::hokuyo
