#include "drivers/v4l2/v4l2_driver.h"

#include <utility>

namespace selfcal::v4l2 {

V4l2Driver::V4l2Driver(DriverOptions options, V4l2Io& io, Bus& bus, LogSink logger)
    : options_(std::move(options)),
      io_(io),
      loop_(options_.stream, options_.request_mode, bus, std::move(logger), counters_) {}

void V4l2Driver::KeepCameraCounters() {
  if (!camera_) return;
  counters_.dropped += camera_->counters().dropped;
  counters_.sequence_gaps += camera_->counters().sequence_gaps;
}

void V4l2Driver::Open() {
  auto camera = V4l2Camera::Open(io_, options_.camera);
  if (!camera) {
    loop_.OpenFailed(camera.error().message);
    return;
  }
  camera_ = std::move(*camera);
  loop_.Opened();
  const Format& f = camera_->format();
  loop_.log()(LogLevel::kInfo, "opened " + options_.camera.device + ": Z16 " +
                                   std::to_string(f.width) + "x" + std::to_string(f.height) + ", " +
                                   std::to_string(f.bytes_per_line) + " bytes per line, " +
                                   std::to_string(f.fps) + " fps");
}

void V4l2Driver::Close(const std::string& why) {
  loop_.log()(LogLevel::kWarning, why + "; reopening every " +
                                      std::to_string(options_.stream.reconnect_period.count()) +
                                      " ms");
  KeepCameraCounters();
  camera_.reset();
}

Expected<bool> V4l2Driver::Publish(const Frame& frame) {
  const camera::DepthImageHeader header{.utime = frame.host_ns / 1000,
                                        .device_utime = frame.device_ns / 1000,
                                        .frame_counter = ++frame_counter_,
                                        .width = static_cast<std::int32_t>(frame.width),
                                        .height = static_cast<std::int32_t>(frame.height),
                                        .depth_unit_m = options_.depth_unit_m,
                                        .intrinsics = options_.intrinsics};
  return loop_.Publish(header);
}

Status V4l2Driver::Run(const std::atomic<bool>& stop) {
  loop_.Begin();
  while (!stop.load()) {
    if (auto status = loop_.ServiceBus(camera_ != nullptr, stop); !status) return status;
    if (!camera_) {
      if (loop_.OpenDue()) Open();
      continue;
    }
    Frame frame;
    auto got = camera_->NextFrame(20, loop_.depth(), frame);
    if (!got) {
      Close(got.error().message);
    } else if (!*got) {
      if (loop_.Silent()) {
        Close("no frame for " + std::to_string(options_.stream.frame_timeout.count()) + " ms");
      }
    } else {
      loop_.FrameReceived();
      if (!loop_.Admit(frame.host_ns / 1000)) continue;
      auto done = Publish(frame);
      if (!done) return done.error();
      if (*done) break;
    }
  }
  KeepCameraCounters();
  return OkStatus();
}

}  // namespace selfcal::v4l2
