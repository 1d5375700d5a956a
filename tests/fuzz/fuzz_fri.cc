// Fuzzes the FRI decoders: any bytes give a message or an error, never a crash; a decoded
// message re-encodes and decodes to the same re-encoding.
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <span>
#include <vector>

#include "protocols/fri/fri_codec.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace selfcal::fri;
  const std::span<const std::uint8_t> bytes(data, size);
  std::vector<std::uint8_t> out(kMaxMessageBytes * 2);
  if (auto monitoring = DecodeMonitoringMessage(bytes); monitoring.ok()) {
    auto n = EncodeMonitoringMessage(*monitoring, out);
    if (!n.ok()) std::abort();
    const std::vector<std::uint8_t> first(out.begin(), out.begin() + static_cast<long>(*n));
    auto again = DecodeMonitoringMessage(first);
    if (*n <= kMaxMessageBytes && !again.ok()) std::abort();
    if (again.ok()) {
      auto m = EncodeMonitoringMessage(*again, out);
      if (!m.ok() || *m != *n || std::memcmp(out.data(), first.data(), *n) != 0) std::abort();
    }
  }
  if (auto command = DecodeCommandMessage(bytes); command.ok()) {
    auto n = EncodeCommandMessage(*command, out);
    if (!n.ok()) std::abort();
    const std::vector<std::uint8_t> first(out.begin(), out.begin() + static_cast<long>(*n));
    auto again = DecodeCommandMessage(first);
    if (*n <= kMaxMessageBytes && !again.ok()) std::abort();
    if (again.ok()) {
      auto m = EncodeCommandMessage(*again, out);
      if (!m.ok() || *m != *n || std::memcmp(out.data(), first.data(), *n) != 0) std::abort();
    }
  }
  return 0;
}
