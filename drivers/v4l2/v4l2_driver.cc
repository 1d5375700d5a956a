#include "drivers/v4l2/v4l2_driver.h"

#include <utility>

namespace selfcal::v4l2 {

V4l2Driver::V4l2Driver(DriverOptions options, V4l2Io& io, Bus& bus, LogSink logger)
    : options_(std::move(options)), io_(io), bus_(bus), log_(std::move(logger)) {}

void V4l2Driver::Close(const std::string& why) {
  log_(LogLevel::kWarning, why + "; reopening every " +
                               std::to_string(options_.stream.reconnect_period.count()) + " ms");
  if (camera_) {
    counters_.dropped += camera_->counters().dropped;
    counters_.sequence_gaps += camera_->counters().sequence_gaps;
  }
  camera_.reset();
}

Status V4l2Driver::Publish(const Frame& frame) {
  const camera::DepthImageHeader header{.utime = frame.host_ns / 1000,
                                        .device_utime = frame.device_ns / 1000,
                                        .frame_counter = ++frame_counter_,
                                        .width = static_cast<std::int32_t>(frame.width),
                                        .height = static_cast<std::int32_t>(frame.height),
                                        .depth_unit_m = options_.depth_unit_m,
                                        .intrinsics = options_.intrinsics};
  return publisher_.Publish(bus_, options_.stream.channel, header, depth_);
}

Status V4l2Driver::Run(const std::atomic<bool>& stop) {
  using Clock = std::chrono::steady_clock;
  if (options_.request_mode) {
    camera::SubscribeScanRequests(bus_, options_.stream.trigger_channel, log_,
                                  [this](std::int64_t utime) {
                                    requests_.push_back(utime);
                                    ++counters_.requests;
                                  });
  }
  auto next_open = Clock::now();
  auto last_frame = Clock::now();
  int failures = 0;
  while (!stop.load()) {
    // Requests are received only in request mode (ServiceBus: why never otherwise);
    // while the camera is away, wait instead of spinning.
    const auto idle_wait = std::chrono::milliseconds(camera_ ? 0 : 20);
    if (auto status = ServiceBus(bus_, options_.request_mode, idle_wait); !status) {
      return stop.load() ? OkStatus() : status;  // EINTR on SIGTERM
    }
    if (!camera_) {
      if (Clock::now() < next_open) continue;
      next_open = Clock::now() + options_.stream.reconnect_period;
      auto camera = V4l2Camera::Open(io_, options_.camera);
      if (!camera) {
        if (failures++ % 20 == 0)
          log_(LogLevel::kWarning, "camera not available: " + camera.error().message);
        continue;
      }
      failures = 0;
      if (opened_once_) ++counters_.reopens;
      opened_once_ = true;
      camera_ = std::move(*camera);
      last_frame = Clock::now();
      const Format& f = camera_->format();
      log_(LogLevel::kInfo, "opened " + options_.camera.device + ": Z16 " +
                                std::to_string(f.width) + "x" + std::to_string(f.height) + ", " +
                                std::to_string(f.bytes_per_line) + " bytes per line, " +
                                std::to_string(f.fps) + " fps");
      continue;
    }
    Frame frame;
    auto got = camera_->NextFrame(20, depth_, frame);
    if (!got) {
      Close(got.error().message);
      continue;
    }
    if (!*got) {
      if (Clock::now() - last_frame > options_.stream.frame_timeout)
        Close("no frame for " + std::to_string(options_.stream.frame_timeout.count()) + " ms");
      continue;
    }
    last_frame = Clock::now();
    if (options_.request_mode) {
      if (requests_.empty() || frame.host_ns / 1000 <= requests_.front()) continue;
      requests_.pop_front();
    }
    if (auto status = Publish(frame); !status) return status;
    ++counters_.published;
    if (options_.stream.Done(counters_.published)) break;
  }
  if (camera_) {
    counters_.dropped += camera_->counters().dropped;
    counters_.sequence_gaps += camera_->counters().sequence_gaps;
  }
  return OkStatus();
}

}  // namespace selfcal::v4l2
