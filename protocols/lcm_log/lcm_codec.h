// Encoding and decoding of lcm-gen types with errors that say what and where.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/util/expected.h"

namespace selfcal {

// Messages above this size are rejected before decoding (a PhotoNeo frame is about 11 MB).
inline constexpr std::size_t kMaxLcmMessageBytes = 64u << 20;

template <typename Message>
std::vector<std::uint8_t> EncodeLcm(const Message& message) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

// Encodes into `buffer`, growing it only when a message is larger than any before, so a driver
// publishing every scan or frame allocates nothing in steady state. Returns the encoded prefix.
template <typename Message>
std::span<const std::uint8_t> EncodeLcmInto(const Message& message,
                                            std::vector<std::uint8_t>& buffer) {
  const auto size = static_cast<std::size_t>(message.getEncodedSize());
  if (buffer.size() < size) buffer.resize(size);
  message.encode(buffer.data(), 0, static_cast<int>(size));
  return {buffer.data(), size};
}

// Decodes `bytes` as `Message`; `where` names the source (channel, log offset) for the error.
// Rejects a wrong fingerprint, truncated or oversized input and trailing bytes.
template <typename Message>
Expected<Message> DecodeLcm(std::span<const std::uint8_t> bytes, const std::string& where) {
  const std::string type = Message::getTypeName();
  if (bytes.size() > kMaxLcmMessageBytes) {
    return Error{where + ": " + type + " message of " + std::to_string(bytes.size()) +
                 " bytes exceeds the limit of " + std::to_string(kMaxLcmMessageBytes)};
  }
  if (bytes.size() < 8) {
    return Error{where + ": " + type + " message truncated: " + std::to_string(bytes.size()) +
                 " bytes, shorter than the 8-byte fingerprint"};
  }
  std::uint64_t fingerprint = 0;
  for (int i = 0; i < 8; ++i) fingerprint = (fingerprint << 8) | bytes[static_cast<std::size_t>(i)];
  if (static_cast<std::int64_t>(fingerprint) != Message::getHash()) {
    return Error{where + ": not a " + type + " message (fingerprint mismatch at byte 0)"};
  }
  Message message;
  const int used = message.decode(bytes.data(), 0, static_cast<int>(bytes.size()));
  if (used < 0) {
    return Error{where + ": " + type + " message of " + std::to_string(bytes.size()) +
                 " bytes is truncated or corrupted (an array or string length exceeds the data)"};
  }
  if (static_cast<std::size_t>(used) != bytes.size()) {
    return Error{where + ": " + type + " message has " +
                 std::to_string(bytes.size() - static_cast<std::size_t>(used)) +
                 " trailing bytes after byte " + std::to_string(used)};
  }
  return message;
}

}  // namespace selfcal
