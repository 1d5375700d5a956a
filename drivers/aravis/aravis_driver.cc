#include "drivers/aravis/aravis_driver.h"

#include <utility>

#include "protocols/lcm_log/lcm_codec.h"

namespace selfcal::aravis {

AravisDriver::AravisDriver(DriverOptions options, Bus& bus, LogSink logger)
    : options_(std::move(options)), bus_(bus), log_(std::move(logger)) {}

bool AravisDriver::Connect() {
  auto camera = AravisCamera::Open(options_.camera);
  if (!camera) {
    if (connect_failures_++ % 20 == 0)
      log_(LogLevel::kWarning, "camera not available: " + camera.error().message);
    return false;
  }
  connect_failures_ = 0;
  camera_ = std::move(*camera);
  if (counters_.published > 0 || counters_.reconnects > 0 || dropped_before_ > 0)
    ++counters_.reconnects;
  block_ids_.Reset();
  trigger_outstanding_ = false;
  log_(LogLevel::kInfo,
       "connected to " + camera_->description() + ", " + std::to_string(camera_->width()) + "x" +
           std::to_string(camera_->height()) + ", " +
           (options_.camera.trigger == TriggerMode::kSoftware ? "software trigger" : "free run"));
  return true;
}

void AravisDriver::Disconnect(const std::string& why) {
  log_(LogLevel::kWarning, "camera lost (" + why + "); reconnecting every " +
                               std::to_string(options_.stream.reconnect_period.count()) + " ms");
  camera_.reset();
  trigger_outstanding_ = false;
}

Status AravisDriver::Publish(const FrameInfo& info) {
  message_.utime = clock_.Map(static_cast<std::int64_t>(info.device_timestamp_ns / 1000),
                              static_cast<std::int64_t>(info.system_timestamp_ns / 1000));
  message_.device_utime = info.device_timestamp_ns > 0
                              ? static_cast<std::int64_t>(info.device_timestamp_ns / 1000)
                              : -1;
  const timing::CounterStep id = block_ids_.Update(static_cast<std::int64_t>(info.frame_id));
  frame_counter_ += id.kind == timing::CounterStepKind::kFirst ? 1 : id.advance;
  message_.frame_counter = frame_counter_;
  message_.width = static_cast<std::int32_t>(info.width);
  message_.height = static_cast<std::int32_t>(info.height);
  // Hand the decoded storage to the message without copying, and take it back after encoding.
  std::swap(message_.x, storage_.x);
  std::swap(message_.y, storage_.y);
  std::swap(message_.z, storage_.z);
  std::swap(message_.intensity, storage_.intensity);
  message_.num_points = static_cast<std::int32_t>(message_.x.size());
  message_.num_intensities = static_cast<std::int32_t>(message_.intensity.size());
  const auto bytes = EncodeLcmInto(message_, encoded_);
  std::swap(message_.x, storage_.x);
  std::swap(message_.y, storage_.y);
  std::swap(message_.z, storage_.z);
  std::swap(message_.intensity, storage_.intensity);
  return bus_.Publish(options_.stream.channel, bytes);
}

Status AravisDriver::Run(const std::atomic<bool>& stop) {
  using Clock = std::chrono::steady_clock;
  const bool triggered = options_.camera.trigger == TriggerMode::kSoftware;
  if (triggered) {
    camera::SubscribeScanRequests(bus_, options_.stream.trigger_channel, log_,
                                  [this](std::int64_t) {
                                    ++pending_requests_;
                                    ++counters_.requests;
                                  });
  }
  auto next_connect = Clock::now();
  auto last_frame = Clock::now();
  int attempts = 0;  // triggers sent for the request at the head of the queue
  while (!stop.load()) {
    // Requests are received only in trigger mode (ServiceBus: why never otherwise);
    // while the camera is away, wait instead of spinning.
    const auto idle_wait = std::chrono::milliseconds(camera_ ? 0 : 20);
    if (auto status = ServiceBus(bus_, triggered, idle_wait); !status) {
      return stop.load() ? OkStatus() : status;  // EINTR on SIGTERM
    }
    const auto now = Clock::now();
    if (!camera_) {
      if (now >= next_connect) {
        next_connect = now + options_.stream.reconnect_period;
        if (Connect()) last_frame = Clock::now();
      }
      continue;
    }
    if (camera_->control_lost()) {
      Disconnect("control lost: no heartbeat answer");
      attempts = 0;
      continue;
    }
    if (triggered && pending_requests_ > 0 && !trigger_outstanding_) {
      if (auto status = camera_->Trigger(); !status) {
        Disconnect(status.error().message);
        attempts = 0;
        continue;
      }
      ++attempts;
      trigger_outstanding_ = true;
      deadline_ = now + options_.stream.frame_timeout;
    }

    const CameraCounters before = camera_->counters();
    FrameInfo info;
    auto got = camera_->NextCloud(std::chrono::milliseconds(10), storage_, info);
    const CameraCounters& after = camera_->counters();
    const std::uint64_t dropped =
        (after.incomplete - before.incomplete) + (after.corrupted - before.corrupted);
    if (dropped > 0) {
      counters_.dropped += dropped;
      dropped_before_ += dropped;
      last_frame = Clock::now();
      log_(LogLevel::kWarning, "dropped " + camera_->last_drop_reason());
      if (trigger_outstanding_) {
        trigger_outstanding_ = false;
        if (attempts > options_.retriggers) {
          --pending_requests_;
          ++counters_.failed_requests;
          attempts = 0;
          log_(LogLevel::kWarning, "trigger request failed after " +
                                       std::to_string(options_.retriggers + 1) + " frames");
        }
      }
    }
    if (got.ok() && *got) {
      last_frame = Clock::now();
      if (triggered && !trigger_outstanding_) {
        ++counters_.stray;  // not asked for: never published in trigger mode
        continue;
      }
      if (auto status = Publish(info); !status) return status.error();
      ++counters_.published;
      if (trigger_outstanding_) {
        trigger_outstanding_ = false;
        --pending_requests_;
        attempts = 0;
      }
      if (options_.stream.Done(counters_.published)) return OkStatus();
      continue;
    }
    const auto later = Clock::now();
    if (trigger_outstanding_ && later > deadline_) {
      Disconnect("no frame " + std::to_string(options_.stream.frame_timeout.count()) +
                 " ms after the trigger");
      attempts = 0;
    } else if (!triggered && later - last_frame > options_.stream.frame_timeout) {
      Disconnect("no frame for " + std::to_string(options_.stream.frame_timeout.count()) + " ms");
    }
  }
  return OkStatus();
}

}  // namespace selfcal::aravis
