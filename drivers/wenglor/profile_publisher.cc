#include "drivers/wenglor/profile_publisher.h"

#include <algorithm>
#include <utility>

namespace selfcal::wenglor {

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
    : columns_(columns),
      queue_(bus, std::move(channel), static_cast<std::size_t>(std::max(queue_profiles, 1)),
             [columns](selfcal::line_profile_t& slot) {
               const auto n = static_cast<std::size_t>(std::max(columns, 0));
               slot.x.reserve(n);
               slot.z.reserve(n);
               slot.intensity.reserve(n);
             }) {}

bool ProfilePublisher::Push(const Profile& profile) {
  return queue_.Submit([&](selfcal::line_profile_t& slot) {
    if (profile.num_points > columns_) return false;
    ToLineProfile(profile, slot);
    return true;
  });
}

PublisherStats ProfilePublisher::stats() const {
  const QueueStats queue = queue_.stats();
  return {queue.published, queue.dropped, queue.failed};
}

}  // namespace selfcal::wenglor
