// Encoding and decoding of FRI monitoring and command messages (protobuf wire format, written by
// hand from the field numbers in ../shared/protocols.md 3.3; KUKA's SDK is not used).
// Pure functions over bytes: no sockets, no logging. Errors name the byte offset and the field.
#pragma once

#include <cstdint>
#include <span>

#include "core/util/expected.h"
#include "protocols/fri/fri_messages.h"

namespace selfcal::fri {

// Decodes a monitoring message (controller -> client). Required fields (header; sessionState and
// quality inside connectionInfo; sec and nanosec inside a timestamp) must be present. Unknown
// fields are skipped as protobuf does; unknown enum values are errors.
Expected<MonitoringMessage> DecodeMonitoringMessage(std::span<const std::uint8_t> bytes);
// Decodes a command message (client -> controller).
Expected<CommandMessage> DecodeCommandMessage(std::span<const std::uint8_t> bytes);

// Encodes into `out` (at most kMaxMessageBytes are needed); returns the number of bytes written,
// or an error when `out` is too small or a JointValues has more than kMaxJointValues entries.
// Fields are written in field-number order, repeated doubles unpacked, as protoc does.
Expected<std::size_t> EncodeMonitoringMessage(const MonitoringMessage& message,
                                              std::span<std::uint8_t> out);
Expected<std::size_t> EncodeCommandMessage(const CommandMessage& message,
                                           std::span<std::uint8_t> out);

}  // namespace selfcal::fri
