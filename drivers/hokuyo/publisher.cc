#include "drivers/hokuyo/publisher.h"

namespace selfcal::hokuyo {

void ToMessage(const RangeScan& scan, range_scan_t& message) {
  message.utime = scan.utime;
  message.device_utime = scan.device_utime;
  message.scan_counter = scan.scan_counter;
  message.time_per_ray = scan.time_per_ray;
  message.angle_first = scan.angle_first;
  message.angle_increment = scan.angle_increment;
  message.num_ranges = static_cast<std::int32_t>(scan.ranges.size());
  message.ranges.assign(scan.ranges.begin(), scan.ranges.end());
  message.num_intensities = static_cast<std::int32_t>(scan.intensities.size());
  message.intensities.assign(scan.intensities.begin(), scan.intensities.end());
}

ScanPublisher::ScanPublisher(Bus& bus, std::string channel, std::size_t capacity,
                             std::size_t max_values)
    : bus_(bus), channel_(std::move(channel)), slots_(capacity) {
  for (auto& slot : slots_) {
    slot.ranges.reserve(max_values);
    slot.intensities.reserve(max_values);
  }
  encoded_.reserve(64 + 8 * max_values);
  thread_ = std::thread([this] { Loop(); });
}

ScanPublisher::~ScanPublisher() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void ScanPublisher::Submit(const RangeScan& scan) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (size_ == slots_.size()) {
      dropped_.fetch_add(1);
      return;
    }
    ToMessage(scan, slots_[(head_ + size_) % slots_.size()]);
    ++size_;
  }
  wake_.notify_one();
}

void ScanPublisher::Flush() {
  std::unique_lock<std::mutex> lock(mutex_);
  drained_.wait(lock, [this] { return size_ == 0 && !busy_; });
}

void ScanPublisher::Loop() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    wake_.wait(lock, [this] { return stop_ || size_ > 0; });
    if (size_ == 0 && stop_) return;
    range_scan_t& message = slots_[head_];
    busy_ = true;
    lock.unlock();
    if (bus_.Publish(channel_, EncodeLcmInto(message, encoded_))) {
      published_.fetch_add(1);
    } else {
      failed_.fetch_add(1);
    }
    lock.lock();
    busy_ = false;
    head_ = (head_ + 1) % slots_.size();
    --size_;
    if (size_ == 0) drained_.notify_all();
  }
}

}  // namespace selfcal::hokuyo
