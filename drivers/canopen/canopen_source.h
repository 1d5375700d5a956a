// Joint states of a CANopen (CiA 402) arm from SYNC-triggered TPDOs, without sockets: frames in,
// samples, frames to send and events out. CanopenDriver does the I/O.
//
// Time: every TPDO that follows a SYNC belongs to that SYNC's instant (the drives latch their
// position actual value on SYNC). When we produce SYNC, the instant is our send time. When
// another master does, the SYNC clock (SYNC index x nominal period) is mapped to host time with
// the drift-aware timing::ClockFilter over the host receive times of the SYNC frames. Either way a
// sample's time is the SYNC instant, not when its last TPDO happened to arrive.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/timing/clock_filter.h"
#include "core/timing/counter_unwrapper.h"
#include "drivers/canopen/canopen_config.h"
#include "protocols/canopen/canopen_frames.h"

namespace selfcal::canopen {

struct JointSample {
  std::int64_t sync_index = 0;     // SYNCs seen since start
  std::int64_t device_us = 0;      // SYNC clock: sync_index x period [us]
  std::int64_t host_us = 0;        // host time of the SYNC instant (clock filter)
  std::vector<double> positions;   // rad, config order
  std::vector<double> velocities;  // rad/s, finite differences between SYNCs (NaN for the first)
};

struct SourceEvent {
  std::string message;
};

class CanopenSource {
 public:
  explicit CanopenSource(CanopenConfig config, timing::ClockFilterOptions clock = {});

  // A frame received at host time `host_us`.
  void OnFrame(const CanFrame& frame, std::int64_t host_us);
  // Frames to send now (NMT start after boot-up, SYNC when producing); call at least every
  // millisecond or so. Also checks heartbeats.
  std::vector<CanFrame> Tick(std::int64_t host_us);

  // Complete samples since the last call (only once the clock filter has settled).
  std::vector<JointSample> TakeSamples();
  std::vector<SourceEvent> TakeEvents();

  const timing::ClockFilter& clock() const { return clock_; }
  std::int64_t syncs() const { return sync_index_; }
  std::int64_t incomplete_syncs() const { return incomplete_; }
  std::int64_t bad_frames() const { return bad_frames_; }
  std::optional<NmtState> node_state(std::uint8_t node) const;

 private:
  void CloseCycle();
  void Event(const std::string& message) { events_.push_back({message}); }

  CanopenConfig config_;
  timing::ClockFilter clock_;
  std::int64_t sync_index_ = -1;
  std::int64_t sync_host_us_ = 0;
  std::int64_t last_sync_sent_us_ = -1;
  // The optional SYNC counter (CiA 301: 1 .. overflow, then 1 again) counts only forward, so
  // its steps say how many SYNCs were missed.
  timing::CounterUnwrapper sync_counter_;
  std::vector<std::optional<std::int32_t>> counts_;  // this SYNC cycle, per joint
  std::vector<double> previous_positions_;
  std::int64_t previous_device_us_ = -1;
  std::int64_t incomplete_ = 0, bad_frames_ = 0;
  bool started_ = false;
  bool cycle_complete_ = false;  // this SYNC cycle's sample was published

  struct Node {
    std::uint8_t id = 0;
    std::optional<NmtState> state;
    std::int64_t last_heartbeat_us = -1;
    bool timed_out = false;
    bool needs_start = false;
  };
  std::vector<Node> nodes_;
  std::vector<JointSample> samples_;
  std::vector<SourceEvent> events_;
};

}  // namespace selfcal::canopen
