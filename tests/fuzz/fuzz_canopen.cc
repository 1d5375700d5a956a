// Any bytes as CAN frames (2 bytes identifier, 1 byte length taken as the socket reported it,
// 8 data bytes) and as cansend text: every decoder returns a value or an error; never a crash or
// a read beyond the frame.
#include <cstdint>
#include <string>

#include "protocols/canopen/canopen_frames.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace selfcal::canopen;
  constexpr std::size_t kRecord = 11;
  for (std::size_t at = 0; at + kRecord <= size; at += kRecord) {
    CanFrame frame;
    frame.id = static_cast<std::uint32_t>(data[at] | data[at + 1] << 8);
    frame.length = data[at + 2];
    for (std::size_t i = 0; i < frame.data.size(); ++i) frame.data[i] = data[at + 3 + i];
    (void)Classify(frame);
    (void)DecodeHeartbeat(frame);
    (void)DecodeSyncCounter(frame);
    for (int offset = -1; offset <= 9; ++offset) {
      if (ReadInt32(frame, offset).ok() && (frame.length > 8 || offset < 0 || offset > 4)) {
        __builtin_trap();
      }
    }
    const std::string text = FormatCansend(frame);
    if (frame.length <= 8 && (frame.id & 0x7ff) == frame.id) {
      // Formatting and parsing round-trip every well-formed frame.
      auto parsed = ParseCansend(text);
      if (!parsed.ok() || parsed->id != frame.id || parsed->length != frame.length) {
        __builtin_trap();
      }
    }
  }
  (void)ParseCansend(std::string(reinterpret_cast<const char*>(data), size));
  return 0;
}
