#include "drivers/canopen/canopen_source.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace selfcal::canopen {

CanopenSource::CanopenSource(CanopenConfig config, timing::ClockFilterOptions clock)
    : config_(std::move(config)),
      clock_(clock),
      sync_counter_({.modulus = std::max(config_.sync_counter_overflow, 2),
                     .first_value = 1,
                     .backwards = timing::CounterOptions::Backwards::kNever}) {
  counts_.resize(config_.joints.size());
  for (const JointConfig& joint : config_.joints) {
    bool known = false;
    for (const Node& node : nodes_) known = known || node.id == joint.node;
    if (!known) nodes_.push_back(Node{joint.node, std::nullopt, -1, false, false});
  }
  samples_.reserve(64);
}

std::optional<NmtState> CanopenSource::node_state(std::uint8_t node) const {
  for (const Node& n : nodes_) {
    if (n.id == node) return n.state;
  }
  return std::nullopt;
}

std::vector<JointSample> CanopenSource::TakeSamples() {
  std::vector<JointSample> taken;
  taken.swap(samples_);
  return taken;
}

std::vector<SourceEvent> CanopenSource::TakeEvents() {
  std::vector<SourceEvent> taken;
  taken.swap(events_);
  return taken;
}

void CanopenSource::CloseCycle() {
  if (sync_index_ >= 0 && !cycle_complete_) ++incomplete_;
  cycle_complete_ = false;
  for (auto& c : counts_) c.reset();
}

void CanopenSource::OnFrame(const CanFrame& frame, std::int64_t host_us) {
  const Classified c = Classify(frame);
  switch (c.kind) {
    case FrameKind::kSync: {
      auto counter = DecodeSyncCounter(frame);
      if (!counter.ok()) {
        ++bad_frames_;
        Event(counter.error().message);
        return;
      }
      CloseCycle();
      // A counter tells how many SYNCs were missed.
      std::int64_t step = 1;
      if (*counter == 0 || config_.sync_counter_overflow == 0) {
        sync_counter_.Reset();
      } else if (const timing::CounterStep s = sync_counter_.Update(*counter);
                 s.kind != timing::CounterStepKind::kFirst) {
        step = s.advance;
      }
      sync_index_ += sync_index_ < 0 ? 1 : step;
      sync_host_us_ = host_us;
      const timing::ClockJump jump =
          clock_.Add(static_cast<std::int64_t>(std::llround(static_cast<double>(sync_index_) *
                                                            config_.sync_period_s * 1e6)),
                     host_us);
      if (jump != timing::ClockJump::kNone) {
        Event("SYNC clock " + std::string(timing::ToString(jump)) + ": clock mapping restarted");
      }
      return;
    }
    case FrameKind::kTpdo: {
      for (std::size_t j = 0; j < config_.joints.size(); ++j) {
        const JointConfig& joint = config_.joints[j];
        if (joint.node != c.node || joint.pdo != c.pdo) continue;
        auto counts = ReadInt32(frame, joint.position_offset);
        if (!counts.ok()) {
          ++bad_frames_;
          Event(joint.name + ": " + counts.error().message);
          continue;
        }
        if (sync_index_ < 0) continue;  // before the first SYNC: no instant to attach it to
        counts_[j] = *counts;
      }
      bool all = sync_index_ >= 0;
      for (const auto& v : counts_) all = all && v.has_value();
      if (!all) return;
      JointSample sample;
      sample.sync_index = sync_index_;
      sample.device_us = static_cast<std::int64_t>(
          std::llround(static_cast<double>(sync_index_) * config_.sync_period_s * 1e6));
      sample.positions.resize(counts_.size());
      for (std::size_t j = 0; j < counts_.size(); ++j) {
        sample.positions[j] = config_.joints[j].ToRadians(*counts_[j]);
      }
      sample.velocities.assign(counts_.size(), std::numeric_limits<double>::quiet_NaN());
      if (previous_device_us_ >= 0 && sample.device_us > previous_device_us_) {
        const double dt = static_cast<double>(sample.device_us - previous_device_us_) * 1e-6;
        for (std::size_t j = 0; j < counts_.size(); ++j) {
          sample.velocities[j] = (sample.positions[j] - previous_positions_[j]) / dt;
        }
      }
      previous_positions_ = sample.positions;
      previous_device_us_ = sample.device_us;
      for (auto& v : counts_) v.reset();  // one sample per SYNC
      cycle_complete_ = true;
      if (config_.produce_sync) {
        // We sent this SYNC: its instant is known exactly, even when a loaded machine sent it
        // late (the SYNC grid then is not regular and no clock fit would describe it).
        sample.host_us = sync_host_us_;
        samples_.push_back(std::move(sample));
      } else if (clock_.settled()) {
        sample.host_us = clock_.ToHost(sample.device_us);
        samples_.push_back(std::move(sample));
      }
      return;
    }
    case FrameKind::kHeartbeat: {
      for (Node& node : nodes_) {
        if (node.id != c.node) continue;
        auto state = DecodeHeartbeat(frame);
        if (!state.ok()) {
          ++bad_frames_;
          Event(state.error().message);
          return;
        }
        if (node.timed_out) Event("node " + std::to_string(node.id) + ": heartbeat back");
        node.timed_out = false;
        node.last_heartbeat_us = host_us;
        if (!node.state || *node.state != *state) {
          Event("node " + std::to_string(node.id) + ": " + ToString(*state));
        }
        node.state = *state;
        if (*state == NmtState::kBootUp && config_.start_nodes) node.needs_start = true;
      }
      return;
    }
    case FrameKind::kEmergency: {
      if (frame.length == 0) return;  // EMCY of length 0: error reset, nothing to report
      const unsigned code = frame.data[0] | (frame.length > 1 ? frame.data[1] << 8 : 0);
      char text[80];
      std::snprintf(text, sizeof(text), "node %u: emergency, error code 0x%04x", c.node, code);
      Event(text);
      return;
    }
    default:
      return;
  }
}

std::vector<CanFrame> CanopenSource::Tick(std::int64_t host_us) {
  std::vector<CanFrame> out;
  if (!started_) {
    started_ = true;
    for (Node& node : nodes_) {
      node.last_heartbeat_us = host_us;  // the timeout runs from start for silent nodes
      if (config_.start_nodes) out.push_back(MakeNmt(NmtCommand::kStart, node.id));
    }
  }
  for (Node& node : nodes_) {
    if (node.needs_start) {
      out.push_back(MakeNmt(NmtCommand::kStart, node.id));
      node.needs_start = false;
    }
    if (!node.timed_out && host_us - node.last_heartbeat_us >
                               static_cast<std::int64_t>(config_.heartbeat_timeout_s * 1e6)) {
      node.timed_out = true;
      Event("node " + std::to_string(node.id) + ": no heartbeat for " +
            std::to_string(config_.heartbeat_timeout_s) + " s");
    }
  }
  if (config_.produce_sync) {
    const auto period_us = static_cast<std::int64_t>(config_.sync_period_s * 1e6);
    if (last_sync_sent_us_ < 0 || host_us - last_sync_sent_us_ >= period_us) {
      // Keep the cadence; after a long stall start again from now.
      last_sync_sent_us_ = (last_sync_sent_us_ < 0 || host_us - last_sync_sent_us_ > 4 * period_us)
                               ? host_us
                               : last_sync_sent_us_ + period_us;
      std::uint8_t counter = 0;
      if (config_.sync_counter_overflow > 0) {
        // The next of 1 .. overflow: our SYNCs are the only ones, one index each.
        counter = static_cast<std::uint8_t>((sync_index_ + 1) % config_.sync_counter_overflow + 1);
      }
      const CanFrame sync = MakeSync(counter);
      out.push_back(sync);
      OnFrame(sync, host_us);  // our own SYNC does not come back on our socket
    }
  }
  return out;
}

}  // namespace selfcal::canopen
