#include "daemon/config.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <sstream>

#include "protocols/model_file/yaml_reader.h"
#include "protocols/program/program.h"

namespace selfcal::daemon {
namespace {

std::string Resolve(const std::string& base_folder, const std::string& path) {
  if (path.empty() || path.front() == '/') return path;
  return (std::filesystem::path(base_folder) / path).lexically_normal().string();
}

void ReadPositive(yaml::StrictMap& map, const std::string& key, double& value) {
  value = map.Optional<double>(key, value);
  if (!(value > 0)) map.Fail(key, "must be positive");
}

void ReadFraction(yaml::StrictMap& map, const std::string& key, double& value) {
  value = map.Optional<double>(key, value);
  if (!(value >= 0 && value < 1)) map.Fail(key, "must be in [0, 1)");
}

void ReadChannels(yaml::StrictMap& channels, ChannelConfig& c) {
  c.joint_state = channels.Optional<std::string>("joint_state", c.joint_state);
  c.sensor = channels.Optional<std::string>("sensor", c.sensor);
  c.scan_marker = channels.Optional<std::string>("scan_marker", c.scan_marker);
  c.calibration_request =
      channels.Optional<std::string>("calibration_request", c.calibration_request);
  c.calibration_status = channels.Optional<std::string>("calibration_status", c.calibration_status);
  c.calibration_result = channels.Optional<std::string>("calibration_result", c.calibration_result);
  c.joint_trajectory = channels.Optional<std::string>("joint_trajectory", c.joint_trajectory);
  c.robot_status = channels.Optional<std::string>("robot_status", c.robot_status);
}

void ReadPlans(yaml::StrictMap& root, const std::string& folder, DaemonConfig& config) {
  auto plans = root.Map("plans");
  for (const auto& item : root.Raw("plans")) {
    const auto name = item.first.as<std::string>();
    config.plans[name] = Resolve(folder, plans.Required<std::string>(name));
  }
  if (config.plans.empty()) root.Fail("plans", "must name at least one plan");
  config.default_plan = root.Required<std::string>("default_plan");
  if (!config.plans.count(config.default_plan)) {
    root.Fail("default_plan", "names a plan that is not under 'plans'");
  }
}

void ReadStorage(yaml::StrictMap& root, const std::string& folder, StorageConfig& config) {
  auto storage = root.Map("storage");
  config.folder = Resolve(folder, storage.Required<std::string>("folder"));
  const double quota_mb = storage.Optional<double>("quota_mb", 2048.0);
  if (!(quota_mb > 0)) storage.Fail("quota_mb", "must be positive");
  config.quota_bytes = static_cast<std::uint64_t>(quota_mb * 1024 * 1024);
  config.requests_kept = storage.Optional<std::int64_t>("requests_kept", config.requests_kept);
  if (config.requests_kept < 1) storage.Fail("requests_kept", "must be at least 1");
  storage.RejectUnknownKeys();
}

void ReadChecks(yaml::StrictMap& checks, CheckConfig& config) {
  ReadPositive(checks, "joint_state_max_age_s", config.joint_state_max_age);
  ReadPositive(checks, "sensor_max_age_s", config.sensor_max_age);
  ReadPositive(checks, "max_deviation", config.max_deviation);
  config.max_lag = checks.Optional<double>("max_lag_s", config.max_lag);
  if (config.max_lag < 0 || config.max_lag > 1) checks.Fail("max_lag_s", "must be in [0, 1]");
  config.limit_margin = checks.Optional<double>("limit_margin", config.limit_margin);
  if (config.limit_margin < 0) checks.Fail("limit_margin", "must not be negative");
}

void ReadMotion(yaml::StrictMap& motion, MotionConfig& config) {
  ReadPositive(motion, "speed_fraction", config.speed_fraction);
  if (config.speed_fraction > 1) motion.Fail("speed_fraction", "must be at most 1");
  config.settle_time = motion.Optional<double>("settle_time_s", config.settle_time);
  if (config.settle_time < 0) motion.Fail("settle_time_s", "must not be negative");
}

void ReadAcceptance(yaml::StrictMap& root, AcceptanceConfig& config) {
  auto acceptance = root.Map("acceptance");
  ReadFraction(acceptance, "min_improvement", config.min_improvement);
  ReadPositive(acceptance, "max_predicted_error_m", config.max_predicted_error);
  config.max_held_out_offset =
      acceptance.Optional<double>("max_held_out_offset_m", config.max_held_out_offset);
  if (!(config.max_held_out_offset >= 0))
    acceptance.Fail("max_held_out_offset_m", "must not be negative (0 = off)");
  config.noise_floor = acceptance.Optional<double>("noise_floor_m", config.noise_floor);
  if (!(config.noise_floor >= 0)) acceptance.Fail("noise_floor_m", "must not be negative");
  ReadPositive(acceptance, "max_angle_change_rad", config.max_angle_change);
  ReadPositive(acceptance, "max_translation_change_m", config.max_translation_change);
  acceptance.RejectUnknownKeys();
}

void ReadCalibration(yaml::StrictMap& calibration, DaemonConfig& config) {
  config.calibration_threads = calibration.Optional<int>("threads", config.calibration_threads);
  if (config.calibration_threads < 1) calibration.Fail("threads", "must be at least 1");
  config.calibration_nice = calibration.Optional<int>("nice", config.calibration_nice);
  if (config.calibration_nice < 0 || config.calibration_nice > 19) {
    calibration.Fail("nice", "must be in [0, 19]");
  }
}

}  // namespace

bool IsValidRobotId(const std::string& id) {
  return !id.empty() && id.size() <= 64 && std::all_of(id.begin(), id.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-';
  });
}

Expected<DaemonConfig> ParseDaemonConfig(const std::string& text, const std::string& path) {
  return yaml::Catching<DaemonConfig>([&] {
    DaemonConfig config;
    config.path = path;
    const std::string folder = std::filesystem::path(path).parent_path().string();
    yaml::StrictMap root(yaml::LoadString(text, path), "", path);
    config.robot_id = root.Required<std::string>("robot_id");
    if (!IsValidRobotId(config.robot_id)) root.Fail("robot_id", kRobotIdRule);
    config.lcm_url = root.Optional<std::string>("lcm_url", config.lcm_url);
    root.OptionalSection("channels", [&](yaml::StrictMap& m) { ReadChannels(m, config.channels); });
    config.robot_model = Resolve(folder, root.Required<std::string>("robot_model"));
    config.sensor = Resolve(folder, root.Required<std::string>("sensor"));
    ReadPlans(root, folder, config);
    ReadStorage(root, folder, config.storage);
    config.key_file = Resolve(folder, root.Required<std::string>("key_file"));
    ReadPositive(root, "request_window_s", config.request_window);
    root.OptionalSection("checks", [&](yaml::StrictMap& m) { ReadChecks(m, config.checks); });
    root.OptionalSection("motion", [&](yaml::StrictMap& m) { ReadMotion(m, config.motion); });
    ReadAcceptance(root, config.acceptance);
    root.OptionalSection("calibration", [&](yaml::StrictMap& m) { ReadCalibration(m, config); });
    ReadPositive(root, "status_rate_hz", config.status_rate_hz);
    if (config.status_rate_hz < 1) root.Fail("status_rate_hz", "must be at least 1");
    root.RejectUnknownKeys();
    return config;
  });
}

std::string InstalledDaemonConfig() { return program::InstalledConfig("daemon.yaml"); }

Expected<DaemonConfig> ReadDaemonConfig(const std::string& path) {
  return yaml::Catching<DaemonConfig>([&] {
    std::ostringstream text;
    text << yaml::LoadFile(path);  // syntax errors name the file
    auto parsed = ParseDaemonConfig(text.str(), path);
    if (!parsed) throw yaml::ParseError(parsed.error().message);
    return std::move(parsed).value();
  });
}

void DescribeSettings(program::Program& program, const DaemonConfig& c) {
  program.Setting("robot_id", c.robot_id);
  program.Setting("lcm_url", c.lcm_url);
  program.Setting("channels.joint_state", c.channels.joint_state);
  program.Setting("channels.sensor", c.channels.sensor);
  program.Setting("channels.scan_marker", c.channels.scan_marker);
  program.Setting("channels.calibration_request", c.channels.calibration_request);
  program.Setting("channels.calibration_status", c.channels.calibration_status);
  program.Setting("channels.calibration_result", c.channels.calibration_result);
  program.Setting("channels.joint_trajectory", c.channels.joint_trajectory);
  program.Setting("channels.robot_status", c.channels.robot_status);
  program.Setting("robot_model", c.robot_model);
  program.Setting("sensor", c.sensor);
  for (const auto& [name, file] : c.plans) program.Setting("plans." + name, file);
  program.Setting("default_plan", c.default_plan);
  program.Setting("storage.folder", c.storage.folder);
  program.EchoValue("storage.quota_mb", [&c] {
    return program::FormatValue(static_cast<double>(c.storage.quota_bytes) / (1024.0 * 1024.0));
  });
  program.Setting("storage.requests_kept", c.storage.requests_kept);
  program.Setting("key_file", c.key_file);
  program.Setting("request_window_s", c.request_window);
  program.Setting("checks.joint_state_max_age_s", c.checks.joint_state_max_age);
  program.Setting("checks.sensor_max_age_s", c.checks.sensor_max_age);
  program.Setting("checks.max_deviation", c.checks.max_deviation);
  program.Setting("checks.max_lag_s", c.checks.max_lag);
  program.Setting("checks.limit_margin", c.checks.limit_margin);
  program.Setting("motion.speed_fraction", c.motion.speed_fraction);
  program.Setting("motion.settle_time_s", c.motion.settle_time);
  program.Setting("acceptance.noise_floor_m", c.acceptance.noise_floor);
  program.Setting("acceptance.min_improvement", c.acceptance.min_improvement);
  program.Setting("acceptance.max_predicted_error_m", c.acceptance.max_predicted_error);
  program.Setting("acceptance.max_held_out_offset_m", c.acceptance.max_held_out_offset);
  program.Setting("acceptance.max_angle_change_rad", c.acceptance.max_angle_change);
  program.Setting("acceptance.max_translation_change_m", c.acceptance.max_translation_change);
  program.Setting("calibration.threads", c.calibration_threads);
  program.Setting("calibration.nice", c.calibration_nice);
  program.Setting("status_rate_hz", c.status_rate_hz);
}

}  // namespace selfcal::daemon
