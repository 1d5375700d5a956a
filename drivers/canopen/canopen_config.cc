#include "drivers/canopen/canopen_config.h"

#include <cmath>
#include <set>

#include "protocols/model_file/yaml_reader.h"
#include "protocols/program/program.h"

namespace selfcal::canopen {

double JointConfig::ToRadians(std::int32_t counts) const {
  return static_cast<double>(direction) * static_cast<double>(counts - zero_counts) * 2.0 * M_PI /
         counts_per_revolution;
}

namespace {

using yaml::StrictMap;

CanopenConfig ReadDocument(StrictMap& map) {
  CanopenConfig config;
  config.interface = map.Required<std::string>("interface");
  if (config.interface.empty() || config.interface.size() >= 16) {
    map.Fail("interface", "must be a network interface name of 1 to 15 characters");
  }
  {
    StrictMap sync = map.Map("sync");
    config.produce_sync = sync.Required<bool>("produce");
    config.sync_period_s = sync.Required<double>("period");
    if (!(config.sync_period_s >= 0.0005 && config.sync_period_s <= 1.0)) {
      sync.Fail("period", "must be within [0.0005, 1] s");
    }
    config.sync_counter_overflow = sync.Optional<int>("counter_overflow", 0);
    if (config.sync_counter_overflow != 0 &&
        (config.sync_counter_overflow < 2 || config.sync_counter_overflow > 240)) {
      sync.Fail("counter_overflow", "must be 0 or within [2, 240] (CiA 301)");
    }
    sync.RejectUnknownKeys();
  }
  config.start_nodes = map.Optional<bool>("start_nodes", true);
  config.heartbeat_timeout_s = map.Optional<double>("heartbeat_timeout", 0.3);
  if (!(config.heartbeat_timeout_s > 0)) map.Fail("heartbeat_timeout", "must be positive");
  const auto joints = map.Sequence("joints");
  if (joints.empty()) map.Fail("joints", "must list at least one joint");
  std::set<std::pair<int, int>> used_slots;
  for (std::size_t i = 0; i < joints.size(); ++i) {
    StrictMap j(joints[i], "joints[" + std::to_string(i) + "]", map.file());
    JointConfig joint;
    joint.name = j.Required<std::string>("name");
    const int node = j.Required<int>("node");
    if (node < 1 || node > 127) j.Fail("node", "must be a node-ID within [1, 127]");
    joint.node = static_cast<std::uint8_t>(node);
    joint.pdo = j.Optional<int>("pdo", 1);
    if (joint.pdo < 1 || joint.pdo > 4) j.Fail("pdo", "must be a TPDO number within [1, 4]");
    joint.position_offset = j.Optional<int>("position_offset", 0);
    if (joint.position_offset < 0 || joint.position_offset > 4) {
      j.Fail("position_offset", "must be within [0, 4] (an INT32 within 8 bytes)");
    }
    joint.counts_per_revolution = j.Required<double>("counts_per_revolution");
    if (!(joint.counts_per_revolution > 0)) j.Fail("counts_per_revolution", "must be positive");
    joint.zero_counts = j.Optional<std::int64_t>("zero_counts", 0);
    joint.direction = j.Optional<int>("direction", 1);
    if (joint.direction != 1 && joint.direction != -1) j.Fail("direction", "must be 1 or -1");
    if (!used_slots.insert({joint.node, joint.pdo}).second) {
      j.Fail("node", "node " + std::to_string(node) + " TPDO " + std::to_string(joint.pdo) +
                         " is already used by another joint");
    }
    j.RejectUnknownKeys();
    config.joints.push_back(joint);
  }
  return config;
}

}  // namespace

Expected<CanopenConfig> ParseCanopenConfig(const std::string& text, const std::string& name) {
  return yaml::ParseDocument<CanopenConfig>(text, name, ReadDocument);
}

Expected<CanopenConfig> ReadCanopenConfig(const std::string& path) {
  return yaml::ReadDocumentFile<CanopenConfig>(path, ReadDocument);
}

void DescribeSettings(program::Program& program, const CanopenConfig& c) {
  program.Setting("interface", c.interface);
  program.Setting("sync.produce", c.produce_sync);
  program.Setting("sync.period", c.sync_period_s);
  program.Setting("sync.counter_overflow", c.sync_counter_overflow);
  program.Setting("start_nodes", c.start_nodes);
  program.Setting("heartbeat_timeout", c.heartbeat_timeout_s);
  for (std::size_t i = 0; i < c.joints.size(); ++i) {
    const JointConfig& joint = c.joints[i];
    const std::string key = "joints[" + std::to_string(i) + "].";
    program.Setting(key + "name", joint.name);
    program.EchoValue(key + "node", [&joint] { return std::to_string(joint.node); });
    program.Setting(key + "pdo", joint.pdo);
    program.Setting(key + "position_offset", joint.position_offset);
    program.Setting(key + "counts_per_revolution", joint.counts_per_revolution);
    program.Setting(key + "zero_counts", joint.zero_counts);
    program.Setting(key + "direction", joint.direction);
  }
}

}  // namespace selfcal::canopen
