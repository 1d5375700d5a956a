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

StreamLoop::StreamLoop(const StreamOptions& options, bool request_mode, Bus& bus, LogSink log,
                       StreamCounters& counters)
    : options_(options),
      request_mode_(request_mode),
      bus_(bus),
      log_(std::move(log)),
      counters_(counters) {}

void StreamLoop::Begin() {
  if (!request_mode_) return;
  SubscribeScanRequests(bus_, options_.trigger_channel, log_, [this](std::int64_t utime) {
    requests_.push_back(utime);
    ++counters_.requests;
  });
}

Status StreamLoop::ServiceBus(bool camera_open, const std::atomic<bool>& stop) {
  // Requests are received only in request mode (selfcal::ServiceBus: why never otherwise).
  const auto idle_wait = std::chrono::milliseconds(camera_open ? 0 : 20);
  auto status = selfcal::ServiceBus(bus_, request_mode_, idle_wait);
  return stop.load() ? OkStatus() : status;
}

bool StreamLoop::OpenDue() {
  if (Clock::now() < next_open_) return false;
  next_open_ = Clock::now() + options_.reconnect_period;
  return true;
}

void StreamLoop::OpenFailed(const std::string& why) {
  if (failures_++ % 20 == 0) log_(LogLevel::kWarning, "camera not available: " + why);
}

void StreamLoop::Opened() {
  failures_ = 0;
  if (opened_before_) ++counters_.reopens;
  opened_before_ = true;
  last_frame_ = Clock::now();
}

void StreamLoop::FrameReceived() { last_frame_ = Clock::now(); }

bool StreamLoop::Silent() const { return Clock::now() - last_frame_ > options_.frame_timeout; }

bool StreamLoop::Admit(std::int64_t utime) {
  if (!request_mode_) return true;
  if (requests_.empty() || utime <= requests_.front()) return false;
  requests_.pop_front();
  return true;
}

Expected<bool> StreamLoop::Publish(const DepthImageHeader& header) {
  if (auto status = publisher_.Publish(bus_, options_.channel, header, depth_); !status) {
    return status.error();
  }
  ++counters_.published;
  return options_.Done(counters_.published);
}

}  // namespace selfcal::camera
