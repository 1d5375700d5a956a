#include "protocols/camera/gvsp.h"

#include <algorithm>
#include <cstring>
#include <string>

namespace selfcal::camera {
namespace {

constexpr std::size_t kLeaderFixedBytes = 12;  // reserved, payload type, timestamp
constexpr std::size_t kImageInfoBytes = 24;
constexpr std::size_t kMultipartPayloadPrefix = 8;  // part id, zone, 48-bit offset

std::uint16_t Get16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}
std::uint32_t Get32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}
std::uint64_t Get64(const std::uint8_t* p) {
  return (std::uint64_t{Get32(p)} << 32) | Get32(p + 4);
}
void Put16(std::vector<std::uint8_t>& out, std::uint32_t v) {
  out.push_back(static_cast<std::uint8_t>(v >> 8));
  out.push_back(static_cast<std::uint8_t>(v));
}
void Put32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  Put16(out, v >> 16);
  Put16(out, v & 0xFFFF);
}
void PutHeader(std::vector<std::uint8_t>& out, std::uint16_t block_id, GvspContent content,
               std::uint32_t packet_id) {
  Put16(out, 0);  // status: success
  Put16(out, block_id);
  Put32(out, (static_cast<std::uint32_t>(content) << 24) | (packet_id & 0x00FFFFFF));
}

std::string At(std::size_t offset) { return " (byte " + std::to_string(offset) + ")"; }

// Width, height, offsets and paddings: the same 20 bytes in an image leader and a part info.
void GetGeometry(const std::uint8_t* p, GvspPartInfo& info) {
  info.width = Get32(p);
  info.height = Get32(p + 4);
  info.x_offset = Get32(p + 8);
  info.y_offset = Get32(p + 12);
  info.x_padding = Get16(p + 16);
  info.y_padding = Get16(p + 18);
}
void PutGeometry(std::vector<std::uint8_t>& out, const GvspPartInfo& info) {
  for (std::uint32_t v : {info.width, info.height, info.x_offset, info.y_offset}) Put32(out, v);
  Put16(out, info.x_padding);
  Put16(out, info.y_padding);
}

}  // namespace

Expected<GvspHeader> DecodeGvspHeader(std::span<const std::uint8_t> packet) {
  if (packet.size() < 8) {
    return Error{"GVSP packet of " + std::to_string(packet.size()) +
                 " bytes is shorter than the 8-byte header" + At(packet.size())};
  }
  GvspHeader header;
  header.status = Get16(packet.data());
  const std::uint32_t infos = Get32(packet.data() + 4);
  header.extended_ids = (infos & 0x80000000u) != 0;
  const auto content = static_cast<std::uint8_t>((infos >> 24) & 0x7F);
  switch (content) {
    case 1:
    case 2:
    case 3:
    case 4:
    case 7:
      break;
    default:
      return Error{"GVSP packet format " + std::to_string(content) + " is not supported" + At(4)};
  }
  header.content = static_cast<GvspContent>(content);
  header.low_bits = infos & 0x00FFFFFF;
  if (header.extended_ids) {
    if (packet.size() < 20) {
      return Error{"GVSP packet with extended ids of " + std::to_string(packet.size()) +
                   " bytes is shorter than its 20-byte header" + At(packet.size())};
    }
    header.block_id = Get64(packet.data() + 8);
    header.packet_id = Get32(packet.data() + 16);
    header.header_bytes = 20;
  } else {
    header.block_id = Get16(packet.data() + 2);
    header.packet_id = header.low_bits;
    header.header_bytes = 8;
  }
  if ((header.status & 0x8000) != 0) {
    return Error{"GVSP packet status 0x" + std::to_string(header.status) + " is an error" + At(0)};
  }
  return header;
}

Status DecodeGvspLeader(std::span<const std::uint8_t> packet, const GvspHeader& header,
                        GvspLeader& leader) {
  const std::size_t base = header.header_bytes;
  if (packet.size() < base + kLeaderFixedBytes) {
    return Error{"GVSP leader of " + std::to_string(packet.size()) + " bytes is truncated" +
                 At(packet.size())};
  }
  const std::uint8_t* p = packet.data() + base;
  leader.payload_type = Get16(p + 2) & 0x3FFF;  // bit 14 flags chunk data
  leader.timestamp = Get64(p + 4);
  leader.parts.clear();
  const std::size_t rest = packet.size() - base - kLeaderFixedBytes;
  p += kLeaderFixedBytes;
  if (leader.payload_type == kGvspPayloadImage) {
    if (rest < kImageInfoBytes) {
      return Error{"GVSP image leader lacks its 24-byte image description" + At(packet.size())};
    }
    GvspPartInfo info;
    info.pixel_format = Get32(p);
    GetGeometry(p + 4, info);
    const std::uint64_t bits = (info.pixel_format >> 16) & 0xFF;
    info.length = (std::uint64_t{info.width} * bits / 8 + info.x_padding) * info.height;
    leader.parts.push_back(info);
    return OkStatus();
  }
  if (leader.payload_type != kGvspPayloadMultipart) {
    return Error{"GVSP payload type " + std::to_string(leader.payload_type) +
                 " is neither image (1) nor multipart (10)" + At(base + 2)};
  }
  // Aravis reads the part count from the low byte of the leader's packet-info word; senders that
  // leave it 0 are read by the room the leader has.
  std::size_t count = header.low_bits & 0xFF;
  if (count == 0) count = rest / kGvspPartInfoBytes;
  if (count == 0) return Error{"GVSP multipart leader describes no part" + At(packet.size())};
  if (count * kGvspPartInfoBytes > rest) {
    return Error{"GVSP multipart leader declares " + std::to_string(count) +
                 " parts but has room for " + std::to_string(rest / kGvspPartInfoBytes) +
                 At(packet.size())};
  }
  if (count > leader.parts.capacity()) {
    return Error{"GVSP multipart leader declares " + std::to_string(count) +
                 " parts, more than the " + std::to_string(leader.parts.capacity()) +
                 " this reader accepts" + At(4)};
  }
  for (std::size_t i = 0; i < count; ++i, p += kGvspPartInfoBytes) {
    GvspPartInfo info;
    info.data_type = Get16(p);
    info.length = (std::uint64_t{Get16(p + 2)} << 32) | Get32(p + 4);
    info.pixel_format = Get32(p + 8);
    info.source_id = p[14];
    info.data_purpose_id = Get16(p + 20);
    info.region_id = Get16(p + 22);
    GetGeometry(p + 24, info);
    leader.parts.push_back(info);
  }
  return OkStatus();
}

std::vector<std::uint8_t> EncodeGvspLeader(std::uint16_t block_id, const GvspLeader& leader) {
  std::vector<std::uint8_t> out;
  const bool multipart = leader.payload_type == kGvspPayloadMultipart;
  PutHeader(out, block_id, GvspContent::kLeader,
            multipart ? static_cast<std::uint32_t>(leader.parts.size() & 0xFF) : 0);
  Put16(out, 0);
  Put16(out, leader.payload_type);
  Put32(out, static_cast<std::uint32_t>(leader.timestamp >> 32));
  Put32(out, static_cast<std::uint32_t>(leader.timestamp));
  if (!multipart) {
    const GvspPartInfo& info = leader.parts.at(0);
    Put32(out, info.pixel_format);
    PutGeometry(out, info);
    return out;
  }
  for (const GvspPartInfo& info : leader.parts) {
    Put16(out, info.data_type);
    Put16(out, static_cast<std::uint32_t>(info.length >> 32));
    Put32(out, static_cast<std::uint32_t>(info.length));
    Put32(out, info.pixel_format);
    Put16(out, 0);
    out.push_back(info.source_id);
    out.push_back(0);  // additional zones
    Put32(out, 0);     // zone directions
    Put16(out, info.data_purpose_id);
    Put16(out, info.region_id);
    PutGeometry(out, info);
    Put32(out, 0);
  }
  return out;
}

std::vector<std::uint8_t> EncodeGvspMultipartPayload(std::uint16_t block_id,
                                                     std::uint32_t packet_id, std::uint8_t part_id,
                                                     std::uint64_t offset,
                                                     std::span<const std::uint8_t> bytes) {
  std::vector<std::uint8_t> out;
  out.reserve(16 + bytes.size());
  PutHeader(out, block_id, GvspContent::kMultipart, packet_id);
  out.push_back(part_id);
  out.push_back(0);
  Put16(out, static_cast<std::uint32_t>(offset >> 32));
  Put32(out, static_cast<std::uint32_t>(offset));
  out.insert(out.end(), bytes.begin(), bytes.end());
  return out;
}

std::vector<std::uint8_t> EncodeGvspImagePayload(std::uint16_t block_id, std::uint32_t packet_id,
                                                 std::span<const std::uint8_t> bytes) {
  std::vector<std::uint8_t> out;
  out.reserve(8 + bytes.size());
  PutHeader(out, block_id, GvspContent::kPayload, packet_id);
  out.insert(out.end(), bytes.begin(), bytes.end());
  return out;
}

std::vector<std::uint8_t> EncodeGvspTrailer(std::uint16_t block_id, std::uint32_t packet_id,
                                            std::uint16_t payload_type, std::uint32_t size_y) {
  std::vector<std::uint8_t> out;
  PutHeader(out, block_id, GvspContent::kTrailer, packet_id);
  Put16(out, 0);
  Put16(out, payload_type);
  Put32(out, size_y);
  return out;
}

std::vector<std::uint8_t> ToExtendedIds(std::span<const std::uint8_t> standard,
                                        std::uint64_t block_id) {
  if (standard.size() < 8) return {};
  const std::uint32_t infos = Get32(standard.data() + 4);
  const auto content = static_cast<std::uint8_t>((infos >> 24) & 0x7F);
  const std::uint32_t low = infos & 0x00FFFFFF;
  const bool leader = content == static_cast<std::uint8_t>(GvspContent::kLeader);
  std::vector<std::uint8_t> out(20 + standard.size() - 8);
  out[0] = standard[0];
  out[1] = standard[1];  // status; bytes 2-3 (flags) stay 0
  const std::uint32_t ext_infos =
      0x80000000u | (std::uint32_t{content} << 24) | (leader ? low : 0u);
  for (std::size_t i = 0; i < 4; ++i)
    out[4 + i] = static_cast<std::uint8_t>(ext_infos >> (24 - 8 * i));
  for (std::size_t i = 0; i < 8; ++i)
    out[8 + i] = static_cast<std::uint8_t>(block_id >> (56 - 8 * i));
  const std::uint32_t packet_id = leader ? 0u : low;
  for (std::size_t i = 0; i < 4; ++i)
    out[16 + i] = static_cast<std::uint8_t>(packet_id >> (24 - 8 * i));
  std::copy(standard.begin() + 8, standard.end(), out.begin() + 20);
  return out;
}

std::vector<std::vector<std::uint8_t>> PacketizeGvspBlock(
    std::uint16_t block_id, const GvspLeader& leader,
    std::span<const std::span<const std::uint8_t>> part_bytes, std::size_t block_bytes) {
  std::vector<std::vector<std::uint8_t>> packets;
  packets.push_back(EncodeGvspLeader(block_id, leader));
  std::uint32_t packet_id = 1;
  const bool multipart = leader.payload_type == kGvspPayloadMultipart;
  std::uint64_t part_start = 0;  // multipart offsets count from the start of the block
  for (std::size_t part = 0; part < part_bytes.size(); ++part) {
    const auto bytes = part_bytes[part];
    for (std::size_t offset = 0; offset < bytes.size(); offset += block_bytes) {
      const auto chunk = bytes.subspan(offset, std::min(block_bytes, bytes.size() - offset));
      packets.push_back(multipart ? EncodeGvspMultipartPayload(block_id, packet_id,
                                                               static_cast<std::uint8_t>(part),
                                                               part_start + offset, chunk)
                                  : EncodeGvspImagePayload(block_id, packet_id, chunk));
      ++packet_id;
    }
    part_start += bytes.size();
  }
  const std::uint32_t size_y = leader.parts.empty() ? 0 : leader.parts[0].height;
  packets.push_back(EncodeGvspTrailer(block_id, packet_id, leader.payload_type, size_y));
  return packets;
}

GvspFrameAssembler::GvspFrameAssembler(std::size_t max_payload_bytes, std::size_t max_parts,
                                       std::size_t image_block_bytes)
    : storage_(max_payload_bytes),
      part_start_(max_parts),
      part_received_(max_parts),
      seen_generation_(max_payload_bytes / 64 + 2 * max_parts + 16),
      image_block_bytes_(image_block_bytes) {
  parts_.reserve(max_parts);
  leader_.parts.reserve(max_parts);
}

void GvspFrameAssembler::Abandon() {
  if (active_) {
    if (broken_) {
      ++counters_.corrupted;
    } else {
      ++counters_.incomplete;
    }
  }
  active_ = false;
  broken_ = false;
}

bool GvspFrameAssembler::BlockComplete() const {
  for (std::size_t i = 0; i < parts_.size(); ++i) {
    if (part_received_[i] != parts_[i].info.length) return false;
  }
  return true;
}

Expected<std::optional<GvspFrame>> GvspFrameAssembler::Push(std::span<const std::uint8_t> packet) {
  auto header = DecodeGvspHeader(packet);
  if (!header) {
    broken_ = active_;
    return header.error();
  }
  if (header->content == GvspContent::kLeader) return OnLeader(packet, *header);
  if (!active_ || header->block_id != block_id_) {
    // A packet of a block whose leader we never saw: that block is lost; count it once by id.
    if (active_) Abandon();
    if (header->content == GvspContent::kTrailer) ++counters_.incomplete;
    return std::optional<GvspFrame>{};
  }
  if (header->content == GvspContent::kTrailer) return OnTrailer();
  return OnPayload(packet, *header);
}

Error GvspFrameAssembler::Corrupt(const GvspHeader& header, const std::string& message) {
  broken_ = active_;
  return Error{"GVSP block " + std::to_string(header.block_id) + " packet " +
               std::to_string(header.packet_id) + ": " + message};
}

GvspFrameAssembler::PushResult GvspFrameAssembler::OnLeader(std::span<const std::uint8_t> packet,
                                                            const GvspHeader& header) {
  Abandon();  // a new block while one is open: the open one lost its trailer
  if (auto status = DecodeGvspLeader(packet, header, leader_); !status) return status.error();
  std::size_t total = 0;
  parts_.clear();
  for (std::size_t i = 0; i < leader_.parts.size(); ++i) {
    const GvspPartInfo& info = leader_.parts[i];
    if (info.length > storage_.size() - total) {
      return Error{"GVSP block " + std::to_string(header.block_id) + ": parts need more than the " +
                   std::to_string(storage_.size()) + " bytes this reader holds (part " +
                   std::to_string(i) + ")"};
    }
    part_start_[i] = total;
    part_received_[i] = 0;
    parts_.push_back({info, std::span<const std::uint8_t>(storage_.data() + total, info.length)});
    total += info.length;
  }
  ++generation_;
  block_id_ = header.block_id;
  active_ = true;
  broken_ = false;
  return std::optional<GvspFrame>{};
}

GvspFrameAssembler::PushResult GvspFrameAssembler::OnTrailer() {
  if (broken_ || !BlockComplete()) {
    Abandon();
    return std::optional<GvspFrame>{};
  }
  active_ = false;
  ++counters_.completed;
  return std::optional<GvspFrame>{
      GvspFrame{block_id_, leader_.payload_type, leader_.timestamp, parts_}};
}

Expected<GvspFrameAssembler::Placement> GvspFrameAssembler::LocateMultipart(
    std::span<const std::uint8_t> packet, const GvspHeader& header) const {
  const std::size_t base = header.header_bytes;
  if (leader_.payload_type != kGvspPayloadMultipart) {
    return Error{"multipart payload packet in an image block" + At(4)};
  }
  if (packet.size() < base + kMultipartPayloadPrefix) return Error{"truncated" + At(packet.size())};
  Placement placement;
  placement.part = packet[base];
  std::uint64_t offset =
      (std::uint64_t{Get16(packet.data() + base + 2)} << 32) | Get32(packet.data() + base + 4);
  placement.bytes = packet.subspan(base + kMultipartPayloadPrefix);
  const std::size_t part = placement.part;
  if (part >= parts_.size()) {
    return Error{"part " + std::to_string(part) + " but the leader declared " +
                 std::to_string(parts_.size()) + At(base)};
  }
  // The offset counts from the start of the block (the parts back to back), as Aravis 0.8
  // places multipart data; make it relative to the part.
  if (offset < part_start_[part]) {
    return Error{"offset " + std::to_string(offset) + " lies before part " + std::to_string(part) +
                 ", which starts at byte " + std::to_string(part_start_[part]) + " of the block" +
                 At(base + 2)};
  }
  placement.offset = offset - part_start_[part];
  return placement;
}

Expected<GvspFrameAssembler::Placement> GvspFrameAssembler::LocatePayload(
    std::span<const std::uint8_t> packet, const GvspHeader& header) const {
  if (header.content == GvspContent::kMultipart) return LocateMultipart(packet, header);
  if (header.content != GvspContent::kPayload) {
    return Error{"packet format not handled inside a block" + At(4)};
  }
  if (leader_.payload_type != kGvspPayloadImage) {
    return Error{"image payload packet in a multipart block" + At(4)};
  }
  Placement placement;
  placement.offset = std::uint64_t{header.packet_id - 1} * image_block_bytes_;
  placement.bytes = packet.subspan(header.header_bytes);
  return placement;
}

GvspFrameAssembler::PushResult GvspFrameAssembler::OnPayload(std::span<const std::uint8_t> packet,
                                                             const GvspHeader& header) {
  if (header.packet_id == 0 || header.packet_id >= seen_generation_.size()) {
    return Corrupt(header, "packet id out of range");
  }
  if (seen_generation_[header.packet_id] == generation_) {
    return std::optional<GvspFrame>{};  // a duplicate (resend): already placed
  }
  auto placement = LocatePayload(packet, header);
  if (!placement) return Corrupt(header, placement.error().message);
  const auto& [part, offset, bytes] = *placement;
  const std::uint64_t length = parts_[part].info.length;
  if (offset > length || bytes.size() > length - offset) {
    return Corrupt(header, "bytes " + std::to_string(offset) + ".." +
                               std::to_string(offset + bytes.size()) + " exceed part " +
                               std::to_string(part) + "'s " + std::to_string(length) + " bytes" +
                               At(header.header_bytes));
  }
  std::memcpy(storage_.data() + part_start_[part] + offset, bytes.data(), bytes.size());
  part_received_[part] += bytes.size();
  seen_generation_[header.packet_id] = generation_;
  return std::optional<GvspFrame>{};
}

}  // namespace selfcal::camera
