// The bus seam: drivers and the daemon publish and subscribe through this interface.
// The one implementation is real LCM (udpm:// on a robot, memq:// and file:// in tests); the seam
// keeps message handling testable without a network (as Drake's DrakeLcmInterface does).
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <utility>

#include "core/util/expected.h"
#include "protocols/bus/udpm_sender.h"
#include "protocols/lcm_log/lcm_codec.h"

namespace selfcal {

struct BusMessage {
  std::string channel;
  std::int64_t receive_utime = 0;  // host time [us] at which the bus received the message
  std::span<const std::uint8_t> data;
};

class Bus {
 public:
  using Handler = std::function<void(const BusMessage&)>;
  virtual ~Bus() = default;

  virtual Status Publish(const std::string& channel, std::span<const std::uint8_t> data) = 0;
  // `channel` is an LCM channel regular expression ("IIWA_STATUS", "SELFCAL_.*").
  virtual void Subscribe(const std::string& channel, Handler handler) = 0;
  // As Subscribe, keeping up to `capacity` messages that wait for HandleOnce (liblcm keeps 30 and
  // drops newer ones beyond: a flood on the channel would drop the messages that matter).
  virtual void SubscribeWithQueue(const std::string& channel, Handler handler, int capacity) {
    (void)capacity;
    Subscribe(channel, std::move(handler));
  }
  // Dispatches at most one message, waiting up to `timeout`. Returns true if one was handled.
  virtual Expected<bool> HandleOnce(std::chrono::milliseconds timeout) = 0;
  // A file descriptor that becomes readable when a message waits (for poll()).
  virtual int FileDescriptor() const = 0;
  virtual const std::string& url() const = 0;

  template <typename Message>
  requires requires(const Message& m) { m.getEncodedSize(); }
  Status Publish(const std::string& channel, const Message& message) {
    const auto bytes = EncodeLcm(message);
    return Publish(channel, std::span<const std::uint8_t>(bytes));
  }
};

// Opens LCM at `url`; the error names the URL and liblcm's reason (e.g. no multicast route).
Expected<std::unique_ptr<Bus>> OpenLcmBus(const std::string& url);

// As above; on udpm:// URLs, messages larger than `pacing.burst_bytes` are published by a
// PacedUdpmSender (same wire format, received by any liblcm subscriber) instead of liblcm's
// back-to-back burst. Other URLs and smaller messages go through liblcm unchanged.
Expected<std::unique_ptr<Bus>> OpenLcmBus(const std::string& url, const PublishPacing& pacing);

// One turn of a driver loop's bus work. `receiving`: handle every pending message, waiting up to
// `idle_wait` for the first. Not receiving: never poll (on udpm:// polling makes liblcm open a
// receive socket and thread that would receive every message this process publishes, since
// multicast loops back to the sender's host); just sleep `idle_wait`.
Status ServiceBus(Bus& bus, bool receiving, std::chrono::milliseconds idle_wait);

}  // namespace selfcal
