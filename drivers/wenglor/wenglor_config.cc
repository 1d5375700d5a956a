#include "drivers/wenglor/wenglor_config.h"

#include "protocols/model_file/yaml_reader.h"

namespace selfcal::wenglor {
namespace {

WenglorConfig ReadDocument(yaml::StrictMap& map) {
  WenglorConfig config;
  config.library_path = map.Optional<std::string>("library_path", config.library_path);
  config.ip = map.Optional<std::string>("ip", config.ip);
  config.port = map.Optional<std::string>("port", config.port);
  config.connect_timeout_ms = map.Optional<int>("connect_timeout_ms", config.connect_timeout_ms);
  config.data_timeout_ms = map.Optional<int>("data_timeout_ms", config.data_timeout_ms);
  config.reconnect_interval_ms =
      map.Optional<int>("reconnect_interval_ms", config.reconnect_interval_ms);
  config.poll_interval_us = map.Optional<int>("poll_interval_us", config.poll_interval_us);
  config.exposure_time_us = map.Optional<int>("exposure_time_us", config.exposure_time_us);
  config.line_time_us = map.Optional<int>("line_time_us", config.line_time_us);
  config.trigger_source =
      map.OptionalChoice("trigger_source", config.trigger_source, kTriggerSourceNames);
  config.encoder_step = map.Optional<int>("encoder_step", config.encoder_step);
  config.signal_selection = map.Optional<int>("signal_selection", config.signal_selection);
  config.signals_per_column = map.Optional<int>("signals_per_column", config.signals_per_column);
  config.max_clock_drift_ppm =
      map.Optional<double>("max_clock_drift_ppm", config.max_clock_drift_ppm);
  config.lcm_url = map.Optional<std::string>("lcm_url", config.lcm_url);
  config.channel = map.Optional<std::string>("channel", config.channel);
  config.queue_profiles = map.Optional<int>("queue_profiles", config.queue_profiles);
  map.RejectUnknownKeys();  // before the checks: a misspelt key is named as such
  const Status valid = ValidateConfig(config);
  if (!valid.ok()) throw yaml::ParseError(map.file() + ": " + valid.error().message);
  return config;
}

}  // namespace

Status ValidateConfig(const WenglorConfig& c) {
  auto fail = [](const std::string& key, const std::string& what) -> Status {
    return Error{key + " " + what};
  };
  if (c.library_path.empty()) return fail("library_path", "must not be empty");
  if (c.ip.empty()) return fail("ip", "must not be empty");
  if (c.port.empty()) return fail("port", "must not be empty");
  if (c.connect_timeout_ms <= 0) return fail("connect_timeout_ms", "must be positive");
  if (c.data_timeout_ms <= 0) return fail("data_timeout_ms", "must be positive");
  if (c.reconnect_interval_ms < 0) return fail("reconnect_interval_ms", "must not be negative");
  if (c.poll_interval_us < 0 || c.poll_interval_us > 100000) {
    return fail("poll_interval_us", "must be within 0 .. 100000");
  }
  // Range of SetExposureTime in the DLL interface description.
  if (c.exposure_time_us < 26 || c.exposure_time_us > 100000) {
    return fail("exposure_time_us",
                "must be within 26 .. 100000 (got " + std::to_string(c.exposure_time_us) + ")");
  }
  if (c.line_time_us <= 0) return fail("line_time_us", "must be positive");
  if (c.line_time_us < c.exposure_time_us) {
    return fail("line_time_us", "must not be shorter than exposure_time_us");
  }
  if (c.encoder_step <= 0) return fail("encoder_step", "must be positive");
  if (c.signal_selection < 0) return fail("signal_selection", "must not be negative");
  if (c.signals_per_column < 1 || c.signals_per_column > 2) {
    return fail("signals_per_column", "must be 1 or 2");
  }
  if (!(c.max_clock_drift_ppm >= 0) || c.max_clock_drift_ppm > 10000) {
    return fail("max_clock_drift_ppm", "must be within 0 .. 10000");
  }
  if (c.lcm_url.empty()) return fail("lcm_url", "must not be empty");
  if (c.channel.empty()) return fail("channel", "must not be empty");
  if (c.queue_profiles < 2) return fail("queue_profiles", "must be at least 2");
  return OkStatus();
}

Expected<WenglorConfig> ReadWenglorConfig(const std::string& path) {
  return yaml::ReadDocumentFile<WenglorConfig>(path, ReadDocument);
}

Expected<WenglorConfig> ParseWenglorConfig(const std::string& text, const std::string& name) {
  return yaml::ParseDocument<WenglorConfig>(text, name, ReadDocument);
}

}  // namespace selfcal::wenglor
