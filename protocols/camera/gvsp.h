// GigE Vision stream protocol (GVSP) packets and the reassembly of one block (frame) from them,
// including GigE Vision 2 multipart payloads (PhotoNeo sends Range, Intensity and Confidence as
// parts of one block). Pure: bytes in, values out; storage is allocated once at construction.
//
// Layout (big-endian), as Aravis' GVSP reader and the GigE Vision 2.x standard lay it out:
//   standard ids: status u16 | block_id u16 | EI(1) format(7) packet_id(24) | data
//   extended ids: status u16 | flags u16    | EI(1) format(7) reserved(24)  | block_id u64 |
//                 packet_id u32 | data
// Leader data:    reserved u16 | payload_type u16 | timestamp u64 (as two u32) | then
//   image (payload type 0x0001): pixel_format u32, width, height, x/y offset u32, x/y padding u16
//   multipart (0x000A): one 48-byte part description per part (GvspPartInfo).
// Payload data:   image: raw bytes at (packet_id - 1) * block size;
//                 multipart: part_id u8 | zone u8 | offset u48 | bytes. The offset counts from the
//                 start of the block, the parts back to back (where Aravis 0.8 puts the data;
//                 checked against it in cameras_aravis_test), not from the start of the part.
// Trailer data:   reserved u16 | payload_type u16 | (image: size_y u32).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/util/expected.h"

namespace selfcal::camera {

enum class GvspContent : std::uint8_t {
  kLeader = 1,
  kTrailer = 2,
  kPayload = 3,
  kAllIn = 4,
  kMultipart = 7,  // a payload packet of a multipart block
};

inline constexpr std::uint16_t kGvspPayloadImage = 0x0001;
inline constexpr std::uint16_t kGvspPayloadMultipart = 0x000A;
inline constexpr std::size_t kGvspPartInfoBytes = 48;

struct GvspHeader {
  std::uint16_t status = 0;
  bool extended_ids = false;
  GvspContent content = GvspContent::kLeader;
  std::uint64_t block_id = 0;
  std::uint32_t packet_id = 0;
  std::uint32_t low_bits = 0;  // low 24 bits of the packet-info word (part count of a leader)
  std::size_t header_bytes = 8;
};

struct GvspPartInfo {
  std::uint16_t data_type = 1;  // 1 = 2D image
  std::uint64_t length = 0;     // bytes of the part
  std::uint32_t pixel_format = 0;
  std::uint8_t source_id = 0;
  std::uint16_t data_purpose_id = 0;  // the component id (ComponentIDValue)
  std::uint16_t region_id = 0;
  std::uint32_t width = 0, height = 0, x_offset = 0, y_offset = 0;
  std::uint16_t x_padding = 0, y_padding = 0;
};

struct GvspLeader {
  std::uint16_t payload_type = 0;
  std::uint64_t timestamp = 0;      // device ticks (ns on PhotoNeo and the Aravis fake camera)
  std::vector<GvspPartInfo> parts;  // one for an image payload
};

// Decoders. Errors give the byte offset in the packet.
Expected<GvspHeader> DecodeGvspHeader(std::span<const std::uint8_t> packet);
Status DecodeGvspLeader(std::span<const std::uint8_t> packet, const GvspHeader& header,
                        GvspLeader& leader);

// Encoders (standard ids), for tests, benchmarks and simulators.
std::vector<std::uint8_t> EncodeGvspLeader(std::uint16_t block_id, const GvspLeader& leader);
std::vector<std::uint8_t> EncodeGvspMultipartPayload(std::uint16_t block_id,
                                                     std::uint32_t packet_id, std::uint8_t part_id,
                                                     std::uint64_t offset,
                                                     std::span<const std::uint8_t> bytes);
std::vector<std::uint8_t> EncodeGvspImagePayload(std::uint16_t block_id, std::uint32_t packet_id,
                                                 std::span<const std::uint8_t> bytes);
std::vector<std::uint8_t> EncodeGvspTrailer(std::uint16_t block_id, std::uint32_t packet_id,
                                            std::uint16_t payload_type, std::uint32_t size_y);
// The same packet with extended ids (GigE Vision 2): 20-byte header with a 64-bit block id and a
// 32-bit packet id; the packet-info word keeps only the format and, in a leader, the part count.
// Multipart blocks need it: with standard ids a multipart leader's part count would occupy its
// packet id (Aravis reads it that way). `standard` is a packet of the encoders above.
std::vector<std::uint8_t> ToExtendedIds(std::span<const std::uint8_t> standard,
                                        std::uint64_t block_id);
// All packets of one block: leader, payload packets of at most `block_bytes` each, trailer.
std::vector<std::vector<std::uint8_t>> PacketizeGvspBlock(
    std::uint16_t block_id, const GvspLeader& leader,
    std::span<const std::span<const std::uint8_t>> part_bytes, std::size_t block_bytes);

struct GvspAssembledPart {
  GvspPartInfo info;
  std::span<const std::uint8_t> data;
};

struct GvspFrame {
  std::uint64_t block_id = 0;
  std::uint16_t payload_type = 0;
  std::uint64_t timestamp = 0;
  std::span<const GvspAssembledPart> parts;  // valid until the next Push
};

struct GvspCounters {
  std::uint64_t completed = 0;
  std::uint64_t incomplete = 0;  // trailer seen (or next leader) with bytes missing: dropped
  std::uint64_t corrupted = 0;   // malformed packets; their block is dropped
};

// Reassembles blocks from packets in arrival order, one block at a time (like a camera stream
// without resends). Frames with missing or corrupted packets are counted and never returned.
class GvspFrameAssembler {
 public:
  // `max_payload_bytes`: the largest block; `image_block_bytes`: payload bytes per packet of an
  // image (non-multipart) block, from GevSCPSPacketSize minus the 36 bytes of IP/UDP/GVSP headers.
  GvspFrameAssembler(std::size_t max_payload_bytes, std::size_t max_parts,
                     std::size_t image_block_bytes);

  // Feeds one packet. Returns a frame when its trailer completes a block with every byte present.
  Expected<std::optional<GvspFrame>> Push(std::span<const std::uint8_t> packet);
  const GvspCounters& counters() const { return counters_; }

 private:
  // Where a payload packet's bytes go: a part and an offset inside it.
  struct Placement {
    std::size_t part = 0;
    std::uint64_t offset = 0;
    std::span<const std::uint8_t> bytes;
  };
  using PushResult = Expected<std::optional<GvspFrame>>;

  PushResult OnLeader(std::span<const std::uint8_t> packet, const GvspHeader& header);
  PushResult OnTrailer();
  PushResult OnPayload(std::span<const std::uint8_t> packet, const GvspHeader& header);
  Expected<Placement> LocateMultipart(std::span<const std::uint8_t> packet,
                                      const GvspHeader& header) const;
  Expected<Placement> LocatePayload(std::span<const std::uint8_t> packet,
                                    const GvspHeader& header) const;
  // Marks the open block broken and says which packet is corrupt.
  Error Corrupt(const GvspHeader& header, const std::string& message);
  void Abandon();
  bool BlockComplete() const;

  std::vector<std::uint8_t> storage_;
  std::vector<GvspAssembledPart> parts_;
  std::vector<std::size_t> part_start_;  // offset of each part in storage_
  std::vector<std::uint64_t> part_received_;
  std::vector<std::uint32_t> seen_generation_;  // per packet id: block generation that saw it
  std::uint32_t generation_ = 0;
  std::size_t image_block_bytes_;
  GvspLeader leader_;
  bool active_ = false;
  bool broken_ = false;
  std::uint64_t block_id_ = 0;
  GvspCounters counters_;
};

}  // namespace selfcal::camera
