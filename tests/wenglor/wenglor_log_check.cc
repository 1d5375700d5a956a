// Reads an LCM log written by selfcal-wenglor and checks its line profiles: every message
// decodes, picture counters are consecutive, every profile has 1280 points.
// Usage: wenglor_log_check LOG MIN_PROFILES. Prints "<n> consecutive profiles".
#include <iostream>
#include <string>

#include "protocols/lcm/channels.h"
#include "protocols/lcm_log/lcm_log.h"
#include "selfcal/line_profile_t.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "error: usage: wenglor_log_check LOG MIN_PROFILES\n";
    return 2;
  }
  auto reader = selfcal::LcmLogReader::Open(argv[1]);
  if (!reader.ok()) {
    std::cerr << "error: " << reader.error().message << "\n";
    return 1;
  }
  const long min_profiles = std::stol(argv[2]);
  selfcal::LogEvent event;
  long profiles = 0;
  std::int64_t last_counter = -1;
  while (reader->Next(event)) {
    if (event.channel != selfcal::channels::kLineProfile) continue;
    auto message = selfcal::DecodeLcm<selfcal::line_profile_t>(
        event.data, std::string(argv[1]) + " event " + std::to_string(event.event_number));
    if (!message.ok()) {
      std::cerr << "error: " << message.error().message << "\n";
      return 1;
    }
    if (last_counter >= 0 && message->device_counter != last_counter + 1) {
      std::cerr << "error: event " << event.event_number << ": counter " << message->device_counter
                << " after " << last_counter << "\n";
      return 1;
    }
    if (message->num_points != 1280) {
      std::cerr << "error: event " << event.event_number << ": " << message->num_points
                << " points\n";
      return 1;
    }
    last_counter = message->device_counter;
    ++profiles;
  }
  if (profiles < min_profiles) {
    std::cerr << "error: " << profiles << " profiles, expected at least " << min_profiles << "\n";
    return 1;
  }
  std::cout << profiles << " consecutive profiles\n";
  return 0;
}
