#include "protocols/camera/camera_stream.h"

#include <utility>

#include "protocols/lcm_log/lcm_codec.h"
#include "selfcal/scan_marker_t.hpp"

namespace selfcal::camera {

void SubscribeScanRequests(Bus& bus, const std::string& channel, LogSink log,
                           std::function<void(std::int64_t utime)> on_request) {
  bus.Subscribe(channel, [log = std::move(log),
                          on_request = std::move(on_request)](const BusMessage& message) {
    auto marker = DecodeLcm<selfcal::scan_marker_t>(message.data, message.channel);
    if (!marker) {
      log(LogLevel::kWarning, "ignoring trigger message: " + marker.error().message);
      return;
    }
    if (marker->event != selfcal::scan_marker_t::BEGIN) return;
    on_request(marker->utime);
  });
}

}  // namespace selfcal::camera
