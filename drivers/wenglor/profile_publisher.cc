#include "drivers/wenglor/profile_publisher.h"

#include <algorithm>
#include <utility>

namespace selfcal::wenglor {
namespace {

void CopyProfile(const Profile& from, Profile& to) {
  to.host_receive_utime = from.host_receive_utime;
  to.utime = from.utime;
  to.device_utime = from.device_utime;
  to.counter = from.counter;
  to.raw_counter = from.raw_counter;
  to.lost_before = from.lost_before;
  to.counter_restarted = from.counter_restarted;
  to.encoder = from.encoder;
  to.user_io = from.user_io;
  to.num_points = from.num_points;
  const auto n = static_cast<std::ptrdiff_t>(from.num_points);
  std::copy_n(from.x.begin(), n, to.x.begin());
  std::copy_n(from.z.begin(), n, to.z.begin());
  std::copy_n(from.intensity.begin(), n, to.intensity.begin());
  std::copy_n(from.peak_width.begin(), n, to.peak_width.begin());
}

}  // namespace

void ToLineProfile(const Profile& profile, selfcal::line_profile_t& message) {
  const auto n = static_cast<std::size_t>(profile.num_points);
  message.utime = profile.utime;
  message.device_utime = profile.device_utime;
  message.device_counter = profile.counter;
  message.num_points = profile.num_points;
  // assign() keeps the capacity, so a message reused for every profile allocates once.
  message.x.assign(profile.x.begin(), profile.x.begin() + static_cast<std::ptrdiff_t>(n));
  message.z.assign(profile.z.begin(), profile.z.begin() + static_cast<std::ptrdiff_t>(n));
  message.intensity.assign(profile.intensity.begin(),
                           profile.intensity.begin() + static_cast<std::ptrdiff_t>(n));
}

ProfilePublisher::ProfilePublisher(Bus& bus, std::string channel, int queue_profiles, int columns)
    : bus_(bus), channel_(std::move(channel)), slots_(static_cast<std::size_t>(queue_profiles)) {
  for (Profile& slot : slots_) slot.Allocate(columns);
  thread_ = std::thread([this] { Run(); });
}

ProfilePublisher::~ProfilePublisher() { Stop(); }

bool ProfilePublisher::Push(const Profile& profile) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (size_ == slots_.size() || profile.num_points > static_cast<int>(slots_[0].x.size())) {
      dropped_.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    CopyProfile(profile, slots_[(head_ + size_) % slots_.size()]);
    ++size_;
  }
  wake_.notify_one();
  return true;
}

void ProfilePublisher::Run() {
  selfcal::line_profile_t message;
  const std::size_t capacity = slots_.empty() ? 0 : slots_[0].x.size();
  message.x.reserve(capacity);
  message.z.reserve(capacity);
  message.intensity.reserve(capacity);
  std::vector<std::uint8_t> bytes;
  Profile current;
  current.Allocate(static_cast<int>(capacity));
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return size_ > 0 || stopping_; });
      if (size_ == 0 && stopping_) return;
      // Swap the slot out so that encoding and publishing run without the lock.
      std::swap(current, slots_[head_]);
      head_ = (head_ + 1) % slots_.size();
      --size_;
    }
    ToLineProfile(current, message);
    const Status status = bus_.Publish(channel_, EncodeLcmInto(message, bytes));
    if (status.ok()) {
      published_.fetch_add(1, std::memory_order_relaxed);
    } else {
      errors_.fetch_add(1, std::memory_order_relaxed);
      std::lock_guard<std::mutex> lock(mutex_);
      last_error_ = status.error().message;
    }
  }
}

void ProfilePublisher::Stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_one();
  if (thread_.joinable()) thread_.join();
}

std::string ProfilePublisher::last_error() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_error_;
}

PublisherStats ProfilePublisher::stats() const {
  return {published_.load(), dropped_.load(), errors_.load()};
}

}  // namespace selfcal::wenglor
