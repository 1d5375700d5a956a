// Configuration of the CANopen joint-state driver (YAML, read strictly; see
// config/drivers/canopen.yaml and docs/robot-side.md).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/util/expected.h"

namespace selfcal::program {
class Program;
}

namespace selfcal::canopen {

struct JointConfig {
  std::string name;
  std::uint8_t node = 1;             // CANopen node-ID 1..127
  int pdo = 1;                       // TPDO 1..4 carrying the position actual value (0x6064)
  int position_offset = 0;           // byte offset of the INT32 within that TPDO
  double counts_per_revolution = 0;  // encoder counts per joint revolution (after the gear)
  std::int64_t zero_counts = 0;      // counts at 0 rad
  int direction = 1;                 // +1 or -1: sign of the joint angle per count
  // rad = direction * (counts - zero_counts) * 2 pi / counts_per_revolution
  double ToRadians(std::int32_t counts) const;
};

struct CanopenConfig {
  std::string interface = "can0";
  bool produce_sync = true;       // the driver is the SYNC producer
  double sync_period_s = 0.005;   // nominal SYNC period; the SYNC clock for time mapping
  int sync_counter_overflow = 0;  // 0: SYNC without counter; 2..240: counter wraps there
  bool start_nodes = true;        // NMT start to each node at start and after its boot-up
  double heartbeat_timeout_s = 0.3;
  std::vector<JointConfig> joints;
};

Expected<CanopenConfig> ReadCanopenConfig(const std::string& path);
Expected<CanopenConfig> ParseCanopenConfig(const std::string& text, const std::string& name);

// Adds every setting of `config` to the program's configuration echo, under its key path in the
// file ("sync.period", "joints[2].node"); `config` must outlive the program's LogConfiguration().
void DescribeSettings(program::Program& program, const CanopenConfig& config);

}  // namespace selfcal::canopen
