// Any bytes as any of our LCM messages: an error or a message, never a crash or a huge allocation.
#include <cstdint>
#include <span>

#include "drake/lcmt_iiwa_command.hpp"
#include "drake/lcmt_iiwa_status.hpp"
#include "protocols/lcm_log/lcm_codec.h"
#include "selfcal/calibration_request_t.hpp"
#include "selfcal/calibration_result_t.hpp"
#include "selfcal/calibration_status_t.hpp"
#include "selfcal/depth_image_t.hpp"
#include "selfcal/joint_state_t.hpp"
#include "selfcal/line_profile_t.hpp"
#include "selfcal/organized_cloud_t.hpp"
#include "selfcal/range_scan_t.hpp"
#include "selfcal/scan_marker_t.hpp"

namespace {

template <typename Message>
void Try(std::span<const std::uint8_t> bytes) {
  // The fuzzer mostly mutates bodies: give it the right fingerprint half of the time.
  std::vector<std::uint8_t> with_hash(bytes.begin(), bytes.end());
  if (!with_hash.empty() && (with_hash[0] & 1)) {
    const auto hash = static_cast<std::uint64_t>(Message::getHash());
    with_hash.insert(with_hash.begin(), 8, 0);
    for (int i = 0; i < 8; ++i) {
      with_hash[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(hash >> (56 - 8 * i));
    }
  }
  const auto decoded = selfcal::DecodeLcm<Message>(with_hash, "fuzz");
  if (decoded.ok() && selfcal::EncodeLcm(*decoded).size() != with_hash.size()) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::span<const std::uint8_t> body(data + 1, size - 1);
  switch (data[0] % 11) {
    case 0:
      Try<selfcal::joint_state_t>(body);
      break;
    case 1:
      Try<selfcal::range_scan_t>(body);
      break;
    case 2:
      Try<selfcal::line_profile_t>(body);
      break;
    case 3:
      Try<selfcal::depth_image_t>(body);
      break;
    case 4:
      Try<selfcal::organized_cloud_t>(body);
      break;
    case 5:
      Try<selfcal::scan_marker_t>(body);
      break;
    case 6:
      Try<selfcal::calibration_request_t>(body);
      break;
    case 7:
      Try<selfcal::calibration_status_t>(body);
      break;
    case 8:
      Try<selfcal::calibration_result_t>(body);
      break;
    case 9:
      Try<drake::lcmt_iiwa_status>(body);
      break;
    default:
      Try<drake::lcmt_iiwa_command>(body);
      break;
  }
  return 0;
}
