#include "drivers/openni2/openni2_driver.h"

#include <utility>

#include "core/timing/host_clock.h"

namespace selfcal::openni2 {
OpenNi2Driver::OpenNi2Driver(DriverOptions options, Bus& bus, LogSink logger)
    : options_(std::move(options)),
      loop_(options_.stream, options_.request_mode, bus, std::move(logger), counters_) {}

Expected<bool> OpenNi2Driver::Publish(std::int64_t utime, const DepthFrame& frame) {
  const camera::DepthImageHeader header{
      .utime = utime,
      .device_utime = static_cast<std::int64_t>(frame.device_timestamp_us),
      .frame_counter = frame.frame_index,
      .width = frame.width,
      .height = frame.height,
      .depth_unit_m = frame.depth_unit_m,
      .intrinsics = camera_->intrinsics()};
  return loop_.Publish(header);
}

Status OpenNi2Driver::Open() {
  auto camera = OpenNi2Camera::Open(options_.camera);
  if (!camera) {
    if (playback()) return camera.error();
    loop_.OpenFailed(camera.error().message);
    return OkStatus();
  }
  camera_ = std::move(*camera);
  loop_.Opened();
  const auto& k = camera_->intrinsics();
  loop_.log()(LogLevel::kInfo, "opened " + camera_->description() + ", " +
                                   std::to_string(camera_->width()) + "x" +
                                   std::to_string(camera_->height()) +
                                   ", fx=" + std::to_string(k.fx) + " fy=" + std::to_string(k.fy) +
                                   " cx=" + std::to_string(k.cx) + " cy=" + std::to_string(k.cy));
  return OkStatus();
}

std::int64_t OpenNi2Driver::HostUtime(const DepthFrame& frame) {
  const auto device_us = static_cast<std::int64_t>(frame.device_timestamp_us);
  if (!playback()) return clock_.Map(device_us, timing::RealtimeUs());
  // A recording keeps device times only: replay them from the moment playback started.
  if (first_device_us_ < 0) first_device_us_ = device_us;
  return playback_epoch_us_ + device_us - first_device_us_;
}

Status OpenNi2Driver::Run(const std::atomic<bool>& stop) {
  loop_.Begin();
  playback_epoch_us_ = timing::RealtimeUs();
  while (!stop.load()) {
    if (auto status = loop_.ServiceBus(camera_ != nullptr, stop); !status) return status;
    if (!camera_) {
      if (!loop_.OpenDue()) continue;
      if (auto opened = Open(); !opened) return opened;
      continue;
    }
    DepthFrame frame;
    auto got = camera_->NextFrame(std::chrono::milliseconds(20), loop_.depth(), frame);
    if (!got) {
      if (playback()) return got.error();
      loop_.log()(LogLevel::kWarning, got.error().message + "; reopening");
      camera_.reset();
      continue;
    }
    if (!*got) {
      if (playback() && camera_->at_end()) return OkStatus();
      if (!playback() && loop_.Silent()) {
        loop_.log()(LogLevel::kWarning, "no depth frame for " +
                                            std::to_string(options_.stream.frame_timeout.count()) +
                                            " ms; reopening");
        camera_.reset();
      }
      continue;
    }
    loop_.FrameReceived();
    ++counters_.frames;
    const std::int64_t utime = HostUtime(frame);
    if (!loop_.Admit(utime)) continue;
    auto done = Publish(utime, frame);
    if (!done) return done.error();
    if (*done) return OkStatus();
  }
  return OkStatus();
}

}  // namespace selfcal::openni2
