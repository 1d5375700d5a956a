// A bounded queue of preallocated LCM messages between a driver's receive loop and a publishing
// thread, so that the receive loop never waits on the bus. When the bus falls behind by the
// queue's capacity, the newest message is dropped and counted: the receive loop must keep draining
// its device, or the device's data would be lost there instead, uncounted.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "protocols/bus/bus.h"
#include "protocols/lcm_log/lcm_codec.h"

namespace selfcal {

struct QueueStats {
  std::int64_t published = 0;
  std::int64_t dropped = 0;  // the queue was full, or the message did not fit its slot
  std::int64_t failed = 0;   // the bus refused it
};

template <typename Message>
class QueuedPublisher {
 public:
  // `prepare` reserves each slot's arrays once, so that filling a slot does not allocate.
  template <typename Prepare>
  QueuedPublisher(Bus& bus, std::string channel, std::size_t capacity, Prepare prepare)
      : bus_(bus), channel_(std::move(channel)), slots_(capacity == 0 ? 1 : capacity) {
    for (Message& slot : slots_) prepare(slot);
    prepare(sending_);
    thread_ = std::thread([this] { Run(); });
  }
  ~QueuedPublisher() { Stop(); }
  QueuedPublisher(const QueuedPublisher&) = delete;
  QueuedPublisher& operator=(const QueuedPublisher&) = delete;

  // Fills the next free slot with `fill(Message&)`, which returns false for data that does not
  // fit a slot. False, and counted as dropped, when the queue is full or the data did not fit.
  template <typename Fill>
  bool Submit(Fill&& fill) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (size_ == slots_.size() || !fill(slots_[(head_ + size_) % slots_.size()])) {
        dropped_.fetch_add(1, std::memory_order_relaxed);
        return false;
      }
      ++size_;
    }
    wake_.notify_one();
    return true;
  }

  // Waits until every submitted message has been published or refused.
  void Flush() {
    std::unique_lock<std::mutex> lock(mutex_);
    drained_.wait(lock, [this] { return size_ == 0 && !busy_; });
  }

  // Publishes what is queued, then stops the thread.
  void Stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable()) thread_.join();
  }

  QueueStats stats() const { return {published_.load(), dropped_.load(), failed_.load()}; }
  std::string last_error() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return last_error_;
  }

 private:
  void Run() {
    std::vector<std::uint8_t> bytes;
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      wake_.wait(lock, [this] { return size_ > 0 || stopping_; });
      if (size_ == 0 && stopping_) return;
      // Swap the slot out so that encoding and publishing run without the lock; the swapped-in
      // message keeps its reserved arrays.
      std::swap(sending_, slots_[head_]);
      head_ = (head_ + 1) % slots_.size();
      --size_;
      busy_ = true;
      lock.unlock();
      const Status status = bus_.Publish(channel_, EncodeLcmInto(sending_, bytes));
      lock.lock();
      busy_ = false;
      if (status.ok()) {
        published_.fetch_add(1, std::memory_order_relaxed);
      } else {
        failed_.fetch_add(1, std::memory_order_relaxed);
        last_error_ = status.error().message;
      }
      if (size_ == 0) drained_.notify_all();
    }
  }

  Bus& bus_;
  std::string channel_;
  std::vector<Message> slots_;
  Message sending_;       // the message being published, outside the queue
  std::size_t head_ = 0;  // next slot to publish
  std::size_t size_ = 0;  // slots waiting
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable drained_;
  bool stopping_ = false;
  bool busy_ = false;
  std::atomic<std::int64_t> published_{0};
  std::atomic<std::int64_t> dropped_{0};
  std::atomic<std::int64_t> failed_{0};
  std::string last_error_;
  std::thread thread_;
};

}  // namespace selfcal
