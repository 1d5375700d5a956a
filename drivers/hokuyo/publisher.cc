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
    : queue_(bus, std::move(channel), capacity, [max_values](range_scan_t& slot) {
        slot.ranges.reserve(max_values);
        slot.intensities.reserve(max_values);
      }) {}

void ScanPublisher::Submit(const RangeScan& scan) {
  queue_.Submit([&scan](range_scan_t& slot) {
    ToMessage(scan, slot);
    return true;
  });
}

}  // namespace selfcal::hokuyo
