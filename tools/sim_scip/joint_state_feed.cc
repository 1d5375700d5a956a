#include "tools/sim_scip/joint_state_feed.h"

#include <ctime>

#include "core/timing/host_clock.h"
#include "selfcal/joint_state_t.hpp"
#include "selfcal/scan_marker_t.hpp"

namespace selfcal::sim_scip {

void FeedJointStates(Bus& bus, const std::string& channel, SceneRangeSource& source,
                     std::int64_t* rejected) {
  bus.Subscribe(channel, [&source, rejected](const BusMessage& message) {
    auto state = DecodeLcm<joint_state_t>(message.data, message.channel);
    const auto& names = source.joint_names();
    if (!state || static_cast<std::size_t>(state->num_joints) != names.size()) {
      if (rejected) ++*rejected;
      return;
    }
    std::vector<double> positions(names.size());
    for (std::size_t j = 0; j < names.size(); ++j) {
      std::size_t index = j;
      if (!state->names.empty()) {
        index = names.size();
        for (std::size_t k = 0; k < state->names.size(); ++k) {
          if (state->names[k] == names[j]) index = k;
        }
        if (index == names.size()) {
          if (rejected) ++*rejected;
          return;
        }
      }
      positions[j] = state->positions[index];
    }
    source.AddJointState(static_cast<double>(state->utime) - timing::RealtimeMinusMonotonicUs(),
                         std::move(positions));
  });
}

void FeedScanMarkers(Bus& bus, const std::string& channel, SceneRangeSource& source,
                     std::int64_t* rejected) {
  bus.Subscribe(channel, [&source, rejected](const BusMessage& message) {
    auto marker = DecodeLcm<scan_marker_t>(message.data, message.channel);
    if (!marker) {
      if (rejected) ++*rejected;
      return;
    }
    source.AddScanMarker(static_cast<double>(marker->utime) - timing::RealtimeMinusMonotonicUs(),
                         marker->scan_index, marker->event == scan_marker_t::BEGIN);
  });
}

}  // namespace selfcal::sim_scip
