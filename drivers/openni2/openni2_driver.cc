#include "drivers/openni2/openni2_driver.h"

#include <utility>

namespace selfcal::openni2 {
namespace {
std::int64_t HostNanoseconds() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}
}  // namespace

OpenNi2Driver::OpenNi2Driver(DriverOptions options, Bus& bus, LogSink logger)
    : options_(std::move(options)), bus_(bus), log_(std::move(logger)) {}

Status OpenNi2Driver::Publish(std::int64_t utime, const DepthFrame& frame) {
  const camera::DepthImageHeader header{
      .utime = utime,
      .device_utime = static_cast<std::int64_t>(frame.device_timestamp_us),
      .frame_counter = frame.frame_index,
      .width = frame.width,
      .height = frame.height,
      .depth_unit_m = frame.depth_unit_m,
      .intrinsics = camera_->intrinsics()};
  return publisher_.Publish(bus_, options_.stream.channel, header, depth_);
}

Status OpenNi2Driver::Run(const std::atomic<bool>& stop) {
  using Clock = std::chrono::steady_clock;
  if (options_.request_mode) {
    camera::SubscribeScanRequests(bus_, options_.stream.trigger_channel, log_,
                                  [this](std::int64_t utime) {
                                    requests_.push_back(utime);
                                    ++counters_.requests;
                                  });
  }
  const bool playback = !options_.camera.oni_path.empty();
  const std::int64_t playback_epoch_us = HostNanoseconds() / 1000;
  std::int64_t first_device_us = -1;
  auto next_connect = Clock::now();
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
      if (Clock::now() < next_connect) continue;
      next_connect = Clock::now() + options_.stream.reconnect_period;
      auto camera = OpenNi2Camera::Open(options_.camera);
      if (!camera) {
        if (playback) return camera.error();
        if (failures++ % 20 == 0)
          log_(LogLevel::kWarning, "camera not available: " + camera.error().message);
        continue;
      }
      if (counters_.frames > 0) ++counters_.reconnects;
      failures = 0;
      camera_ = std::move(*camera);
      last_frame = Clock::now();
      const auto& k = camera_->intrinsics();
      log_(LogLevel::kInfo, "opened " + camera_->description() + ", " +
                                std::to_string(camera_->width()) + "x" +
                                std::to_string(camera_->height()) + ", fx=" + std::to_string(k.fx) +
                                " fy=" + std::to_string(k.fy) + " cx=" + std::to_string(k.cx) +
                                " cy=" + std::to_string(k.cy));
      continue;
    }
    DepthFrame frame;
    auto got = camera_->NextFrame(std::chrono::milliseconds(20), depth_, frame);
    if (!got) {
      if (playback) return got.error();
      log_(LogLevel::kWarning, got.error().message + "; reopening");
      camera_.reset();
      continue;
    }
    if (!*got) {
      if (playback && camera_->at_end()) return OkStatus();
      if (!playback && Clock::now() - last_frame > options_.stream.frame_timeout) {
        log_(LogLevel::kWarning, "no depth frame for " +
                                     std::to_string(options_.stream.frame_timeout.count()) +
                                     " ms; reopening");
        camera_.reset();
      }
      continue;
    }
    last_frame = Clock::now();
    ++counters_.frames;
    std::int64_t utime;
    if (playback) {
      // A recording keeps device times only: replay them from the moment playback started.
      if (first_device_us < 0)
        first_device_us = static_cast<std::int64_t>(frame.device_timestamp_us);
      utime = playback_epoch_us + static_cast<std::int64_t>(frame.device_timestamp_us) -
              first_device_us;
    } else {
      utime = clock_.Map(static_cast<std::int64_t>(frame.device_timestamp_us),
                         HostNanoseconds() / 1000);
    }
    if (options_.request_mode) {
      if (requests_.empty() || utime <= requests_.front()) continue;
      requests_.pop_front();
    }
    if (auto status = Publish(utime, frame); !status) return status;
    ++counters_.published;
    if (options_.stream.Done(counters_.published)) return OkStatus();
  }
  return OkStatus();
}

}  // namespace selfcal::openni2
