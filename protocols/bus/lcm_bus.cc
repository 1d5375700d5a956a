#include <lcm/lcm-cpp.hpp>
#include <list>
#include <thread>

#include "protocols/bus/bus.h"

namespace selfcal {
namespace {

class LcmBus final : public Bus {
 public:
  explicit LcmBus(const std::string& url) : url_(url), lcm_(url) {}
  bool good() { return lcm_.good(); }

  void SetPacedSender(std::unique_ptr<PacedUdpmSender> sender) { paced_ = std::move(sender); }

  Status Publish(const std::string& channel, std::span<const std::uint8_t> data) override {
    if (paced_ && data.size() > paced_->pacing().burst_bytes) {
      if (auto status = paced_->Publish(channel, data); !status)
        return Error{url_ + ": " + status.error().message};
      return OkStatus();
    }
    if (lcm_.publish(channel, data.data(), static_cast<unsigned int>(data.size())) != 0) {
      return Error{url_ + ": cannot publish " + std::to_string(data.size()) + " bytes on " +
                   channel};
    }
    return OkStatus();
  }

  void Subscribe(const std::string& channel, Handler handler) override {
    handlers_.push_back(std::move(handler));
    lcm_.subscribeFunction(channel, &LcmBus::Dispatch, &handlers_.back());
  }

  void SubscribeWithQueue(const std::string& channel, Handler handler, int capacity) override {
    handlers_.push_back(std::move(handler));
    lcm_.subscribeFunction(channel, &LcmBus::Dispatch, &handlers_.back())
        ->setQueueCapacity(capacity);
  }

  Expected<bool> HandleOnce(std::chrono::milliseconds timeout) override {
    const int rc = lcm_.handleTimeout(static_cast<int>(timeout.count()));
    if (rc < 0) return Error{url_ + ": LCM receive failed"};
    return rc > 0;
  }

  int FileDescriptor() const override { return const_cast<lcm::LCM&>(lcm_).getFileno(); }
  const std::string& url() const override { return url_; }

 private:
  static void Dispatch(const lcm::ReceiveBuffer* buffer, const std::string& channel,
                       Handler* handler) {
    const auto* begin = static_cast<const std::uint8_t*>(buffer->data);
    (*handler)(BusMessage{channel, buffer->recv_utime, {begin, buffer->data_size}});
  }

  std::string url_;
  lcm::LCM lcm_;
  std::list<Handler> handlers_;  // stable addresses: liblcm keeps a pointer to each
  std::unique_ptr<PacedUdpmSender> paced_;
};

}  // namespace

Expected<std::unique_ptr<Bus>> OpenLcmBus(const std::string& url) {
  return OpenLcmBus(url, PublishPacing{});
}

Expected<std::unique_ptr<Bus>> OpenLcmBus(const std::string& url, const PublishPacing& pacing) {
  auto bus = std::make_unique<LcmBus>(url);
  if (!bus->good()) {
    return Error{"cannot open LCM at '" + url +
                 "' (for udpm:// check the multicast route: ip route add 224.0.0.0/4 dev lo)"};
  }
  const std::string effective = EffectiveLcmUrl(url);
  if (pacing.burst_bytes > 0 && effective.rfind("udpm://", 0) == 0) {
    auto endpoint = ParseUdpmUrl(effective);
    if (!endpoint) return endpoint.error();
    auto sender = PacedUdpmSender::Open(*endpoint, pacing);
    if (!sender) return sender.error();
    bus->SetPacedSender(std::move(*sender));
  }
  return std::unique_ptr<Bus>(std::move(bus));
}

Status ServiceBus(Bus& bus, bool receiving, std::chrono::milliseconds idle_wait) {
  if (!receiving) {
    std::this_thread::sleep_for(idle_wait);
    return OkStatus();
  }
  for (auto wait = idle_wait;; wait = std::chrono::milliseconds(0)) {
    auto handled = bus.HandleOnce(wait);
    if (!handled) return handled.error();
    if (!*handled) return OkStatus();
  }
}

}  // namespace selfcal
