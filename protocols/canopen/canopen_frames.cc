#include "protocols/canopen/canopen_frames.h"

#include <cctype>
#include <cstdio>

namespace selfcal::canopen {

Classified Classify(const CanFrame& frame) {
  const std::uint32_t id = frame.id & 0x7ff;
  const auto node = static_cast<std::uint8_t>(id & 0x7f);
  const std::uint32_t function = id & 0x780;
  if (id == 0x000) return {FrameKind::kNmt, 0, 0};
  if (id == 0x080) return {FrameKind::kSync, 0, 0};
  if (node == 0) return {FrameKind::kOther, 0, 0};
  switch (function) {
    case 0x080:
      return {FrameKind::kEmergency, node, 0};
    case 0x180:
      return {FrameKind::kTpdo, node, 1};
    case 0x280:
      return {FrameKind::kTpdo, node, 2};
    case 0x380:
      return {FrameKind::kTpdo, node, 3};
    case 0x480:
      return {FrameKind::kTpdo, node, 4};
    case 0x200:
      return {FrameKind::kRpdo, node, 1};
    case 0x300:
      return {FrameKind::kRpdo, node, 2};
    case 0x400:
      return {FrameKind::kRpdo, node, 3};
    case 0x500:
      return {FrameKind::kRpdo, node, 4};
    case 0x580:
      return {FrameKind::kSdoResponse, node, 0};
    case 0x600:
      return {FrameKind::kSdoRequest, node, 0};
    case 0x700:
      return {FrameKind::kHeartbeat, node, 0};
    default:
      return {FrameKind::kOther, node, 0};
  }
}

const char* ToString(NmtState state) {
  switch (state) {
    case NmtState::kBootUp:
      return "boot-up";
    case NmtState::kStopped:
      return "stopped";
    case NmtState::kOperational:
      return "operational";
    case NmtState::kPreOperational:
      return "pre-operational";
  }
  return "unknown";
}

CanFrame MakeNmt(NmtCommand command, std::uint8_t node) {
  CanFrame frame;
  frame.id = 0x000;
  frame.length = 2;
  frame.data[0] = static_cast<std::uint8_t>(command);
  frame.data[1] = node;
  return frame;
}

CanFrame MakeSync(std::uint8_t counter) {
  CanFrame frame;
  frame.id = 0x080;
  frame.length = counter == 0 ? 0 : 1;
  frame.data[0] = counter;
  return frame;
}

Expected<NmtState> DecodeHeartbeat(const CanFrame& frame) {
  const std::string where = "heartbeat of node " + std::to_string(frame.id & 0x7f);
  if (frame.length != 1) {
    return Error{where + ": " + std::to_string(frame.length) + " bytes, expected 1"};
  }
  const std::uint8_t state = frame.data[0] & 0x7f;  // bit 7 is the toggle of node guarding
  switch (state) {
    case 0x00:
    case 0x04:
    case 0x05:
    case 0x7f:
      return static_cast<NmtState>(state);
    default: {
      char hex[8];
      std::snprintf(hex, sizeof(hex), "0x%02x", frame.data[0]);
      return Error{where + ": byte 0: unknown NMT state " + hex};
    }
  }
}

Expected<std::uint8_t> DecodeSyncCounter(const CanFrame& frame) {
  if (frame.length == 0) return static_cast<std::uint8_t>(0);
  if (frame.length == 1) return frame.data[0];
  return Error{"SYNC: " + std::to_string(frame.length) + " bytes, expected 0 or 1"};
}

Expected<std::int32_t> ReadInt32(const CanFrame& frame, int offset) {
  char id[8];
  std::snprintf(id, sizeof(id), "0x%03x", frame.id & 0x7ff);
  if (frame.length > frame.data.size()) {
    return Error{std::string("PDO ") + id + ": length " + std::to_string(frame.length) +
                 " exceeds the " + std::to_string(frame.data.size()) + " bytes of a CAN frame"};
  }
  if (offset < 0 || offset + 4 > frame.length) {
    return Error{std::string("PDO ") + id + ": INT32 at byte " + std::to_string(offset) +
                 " does not fit into " + std::to_string(frame.length) + " bytes"};
  }
  const auto k = static_cast<std::size_t>(offset);
  const std::uint32_t raw = static_cast<std::uint32_t>(frame.data[k]) |
                            static_cast<std::uint32_t>(frame.data[k + 1]) << 8 |
                            static_cast<std::uint32_t>(frame.data[k + 2]) << 16 |
                            static_cast<std::uint32_t>(frame.data[k + 3]) << 24;
  return static_cast<std::int32_t>(raw);
}

Expected<CanFrame> ParseCansend(const std::string& text) {
  const auto hash = text.find('#');
  if (hash == std::string::npos || hash == 0 || hash > 3) {
    return Error{"'" + text + "': expected III#DD.. with a 3-digit identifier"};
  }
  CanFrame frame;
  for (std::size_t i = 0; i < hash; ++i) {
    if (!std::isxdigit(static_cast<unsigned char>(text[i]))) {
      return Error{"'" + text + "': character " + std::to_string(i) + " is not hexadecimal"};
    }
  }
  frame.id = static_cast<std::uint32_t>(std::stoul(text.substr(0, hash), nullptr, 16));
  if (frame.id > 0x7ff) return Error{"'" + text + "': identifier above 0x7ff"};
  std::string payload;
  for (std::size_t i = hash + 1; i < text.size(); ++i) {
    if (text[i] == '.') continue;
    if (!std::isxdigit(static_cast<unsigned char>(text[i]))) {
      return Error{"'" + text + "': character " + std::to_string(i) + " is not hexadecimal"};
    }
    payload.push_back(text[i]);
  }
  if (payload.size() % 2 != 0 || payload.size() > 16) {
    return Error{"'" + text + "': payload must be 0 to 8 whole bytes"};
  }
  frame.length = static_cast<std::uint8_t>(payload.size() / 2);
  for (std::size_t i = 0; i < frame.length; ++i) {
    frame.data[i] = static_cast<std::uint8_t>(std::stoul(payload.substr(2 * i, 2), nullptr, 16));
  }
  return frame;
}

std::string FormatCansend(const CanFrame& frame) {
  char text[32];
  int n = std::snprintf(text, sizeof(text), "%03X#", frame.id & 0x7ff);
  for (std::size_t i = 0; i < frame.length && i < 8; ++i) {
    n += std::snprintf(text + n, sizeof(text) - static_cast<std::size_t>(n), "%02X", frame.data[i]);
  }
  return text;
}

}  // namespace selfcal::canopen
