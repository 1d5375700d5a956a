// CANopen (CiA 301) frames as far as a joint-state reader needs them, pure functions over
// frames: NMT commands, SYNC (with the optional counter), heartbeat / boot-up, TPDOs, EMCY.
// COB-IDs of the predefined connection set: NMT 0x000, SYNC 0x080, EMCY 0x080 + node,
// TPDO1..4 0x180/0x280/0x380/0x480 + node, SDO 0x580/0x600 + node, heartbeat 0x700 + node.
// CiA 402 drives report "position actual value" (object 0x6064, INT32, little endian) in
// encoder counts; where it sits in a TPDO is configuration (the PDO mapping of the drive).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "core/util/expected.h"

namespace selfcal::canopen {

// One classic CAN frame (11-bit identifiers; CANopen uses no extended frames).
struct CanFrame {
  std::uint32_t id = 0;  // 11-bit COB-ID
  std::uint8_t length = 0;
  std::array<std::uint8_t, 8> data{};
};

enum class FrameKind {
  kNmt,
  kSync,
  kEmergency,
  kTpdo,
  kRpdo,
  kSdoResponse,
  kSdoRequest,
  kHeartbeat,
  kOther
};

struct Classified {
  FrameKind kind = FrameKind::kOther;
  std::uint8_t node = 0;  // 1..127 for node-specific frames
  int pdo = 0;            // 1..4 for TPDO/RPDO
};
Classified Classify(const CanFrame& frame);

// NMT node states as a heartbeat reports them.
enum class NmtState : std::uint8_t {
  kBootUp = 0x00,
  kStopped = 0x04,
  kOperational = 0x05,
  kPreOperational = 0x7f,
};
const char* ToString(NmtState state);

enum class NmtCommand : std::uint8_t {
  kStart = 0x01,
  kStop = 0x02,
  kEnterPreOperational = 0x80,
  kResetNode = 0x81,
  kResetCommunication = 0x82,
};

CanFrame MakeNmt(NmtCommand command, std::uint8_t node);  // node 0 = all nodes
// SYNC with a counter (1..240, CiA 301) or without (counter 0 -> empty frame).
CanFrame MakeSync(std::uint8_t counter = 0);

// The heartbeat's state; errors name the node and byte when it is not one byte of a known state.
Expected<NmtState> DecodeHeartbeat(const CanFrame& frame);
// SYNC counter, 0 when the frame carries none; error for a SYNC of 2..8 bytes.
Expected<std::uint8_t> DecodeSyncCounter(const CanFrame& frame);
// A little-endian INT32 at `offset` of a PDO; the error names the COB-ID, offset and length.
Expected<std::int32_t> ReadInt32(const CanFrame& frame, int offset);

// cansend's text form "1A3#DEADBEEF" (used by tests and logs); error names the position.
Expected<CanFrame> ParseCansend(const std::string& text);
std::string FormatCansend(const CanFrame& frame);

}  // namespace selfcal::canopen
