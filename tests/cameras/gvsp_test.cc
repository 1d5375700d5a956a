// GVSP multipart blocks built to the GigE Vision layout, reassembled and decoded to a cloud.
#include "protocols/camera/gvsp.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "protocols/camera/cloud_decode.h"
#include "protocols/camera/pixel_format.h"

namespace selfcal::camera {
namespace {

constexpr std::uint32_t kWidth = 7, kHeight = 5;

std::vector<std::uint8_t> FloatBytes(const std::vector<float>& values) {
  std::vector<std::uint8_t> bytes(values.size() * 4);
  std::memcpy(bytes.data(), values.data(), bytes.size());
  return bytes;
}

// A PhotoNeo-like block: Intensity (Mono16, id 1), Range (Coord3D_ABC32f mm, id 4),
// Confidence (Confidence8, id 6), parts in increasing component id order. Every pixel's value is
// distinct so that a swapped row, column or part fails.
struct Block {
  GvspLeader leader;
  std::vector<std::uint8_t> intensity, range, confidence;
};

Block MakeBlock() {
  Block block;
  block.leader.payload_type = kGvspPayloadMultipart;
  block.leader.timestamp = 0x0123456789ABCDEFull;
  std::vector<float> xyz;
  for (std::uint32_t r = 0; r < kHeight; ++r) {
    for (std::uint32_t c = 0; c < kWidth; ++c) {
      xyz.push_back(10.0f * static_cast<float>(c) - 30.0f);
      xyz.push_back(-5.0f * static_cast<float>(r));
      xyz.push_back(500.0f + static_cast<float>(r * kWidth + c));
      const auto i = static_cast<std::uint16_t>(1000 + r * kWidth + c);
      block.intensity.push_back(static_cast<std::uint8_t>(i & 0xFF));
      block.intensity.push_back(static_cast<std::uint8_t>(i >> 8));
      // Confidence 0 (invalid) on the diagonal.
      block.confidence.push_back(r == c ? 0 : static_cast<std::uint8_t>(100 + c));
    }
  }
  block.range = FloatBytes(xyz);
  const auto part = [](std::uint32_t format, std::uint16_t id, std::size_t length) {
    GvspPartInfo info;
    info.pixel_format = format;
    info.data_purpose_id = id;
    info.width = kWidth;
    info.height = kHeight;
    info.length = length;
    return info;
  };
  block.leader.parts = {part(pfnc::kMono16, 1, block.intensity.size()),
                        part(pfnc::kCoord3dAbc32f, 4, block.range.size()),
                        part(pfnc::kConfidence8, 6, block.confidence.size())};
  return block;
}

std::vector<std::vector<std::uint8_t>> Packets(const Block& block, std::uint16_t id,
                                               std::size_t block_bytes = 64) {
  const std::span<const std::uint8_t> parts[] = {block.intensity, block.range, block.confidence};
  return PacketizeGvspBlock(id, block.leader, parts, block_bytes);
}

std::vector<ImagePart> ToImageParts(const GvspFrame& frame) {
  std::vector<ImagePart> parts;
  for (const auto& part : frame.parts) {
    ImagePart image;
    image.role = ClassifyByPixelFormat(part.info.pixel_format);
    image.pixel_format = part.info.pixel_format;
    image.width = part.info.width;
    image.height = part.info.height;
    image.x_padding = part.info.x_padding;
    image.data = part.data;
    parts.push_back(image);
  }
  return parts;
}

TEST(Gvsp, MultipartBlockRoundTripsThroughAssemblerAndDecodesToMetres) {
  const Block block = MakeBlock();
  GvspFrameAssembler assembler(1 << 16, 8, 64);
  std::optional<GvspFrame> frame;
  for (const auto& packet : Packets(block, 42)) {
    auto pushed = assembler.Push(packet);
    ASSERT_TRUE(pushed.ok()) << pushed.error().message;
    if (pushed->has_value()) frame = **pushed;
  }
  ASSERT_TRUE(frame.has_value());
  EXPECT_EQ(frame->block_id, 42u);
  EXPECT_EQ(frame->timestamp, 0x0123456789ABCDEFull);
  ASSERT_EQ(frame->parts.size(), 3u);
  EXPECT_EQ(frame->parts[1].info.data_purpose_id, 4);
  EXPECT_EQ(frame->parts[1].info.pixel_format, pfnc::kCoord3dAbc32f);
  EXPECT_TRUE(std::equal(block.range.begin(), block.range.end(), frame->parts[1].data.begin()));

  const auto parts = ToImageParts(*frame);
  std::vector<float> x(kWidth * kHeight), y(x.size()), z(x.size()), intensity(x.size());
  auto summary = DecodeOrganizedCloud(parts, {}, {}, {kWidth, kHeight, x, y, z, intensity});
  ASSERT_TRUE(summary.ok()) << summary.error().message;
  EXPECT_EQ(summary->valid_points, kWidth * kHeight - kHeight);  // the diagonal is invalid
  EXPECT_TRUE(summary->has_intensity);
  for (std::uint32_t r = 0; r < kHeight; ++r) {
    for (std::uint32_t c = 0; c < kWidth; ++c) {
      const std::size_t i = r * kWidth + c;
      EXPECT_FLOAT_EQ(intensity[i], static_cast<float>(1000 + i));
      if (r == c) {
        EXPECT_TRUE(std::isnan(x[i]) && std::isnan(y[i]) && std::isnan(z[i])) << r << "," << c;
        continue;
      }
      EXPECT_NEAR(x[i], 0.010 * c - 0.030, 1e-6);
      EXPECT_NEAR(y[i], -0.005 * r, 1e-6);
      EXPECT_NEAR(z[i], 0.500 + 0.001 * static_cast<double>(i), 1e-6);
    }
  }
}

TEST(Gvsp, ReorderedPayloadPacketsStillAssemble) {
  const Block block = MakeBlock();
  auto packets = Packets(block, 3, 40);
  std::mt19937 rng(7);
  std::shuffle(packets.begin() + 1, packets.end() - 1, rng);
  GvspFrameAssembler assembler(1 << 16, 8, 40);
  int frames = 0;
  for (const auto& packet : packets) {
    auto pushed = assembler.Push(packet);
    ASSERT_TRUE(pushed.ok()) << pushed.error().message;
    frames += pushed->has_value();
  }
  EXPECT_EQ(frames, 1);
}

TEST(Gvsp, LostPacketDropsTheBlockAndCountsIt) {
  const Block block = MakeBlock();
  GvspFrameAssembler assembler(1 << 16, 8, 64);
  int frames = 0;
  for (int id = 1; id <= 3; ++id) {
    auto packets = Packets(block, static_cast<std::uint16_t>(id));
    if (id == 2) packets.erase(packets.begin() + 4);  // a payload packet lost on the wire
    for (const auto& packet : packets) {
      auto pushed = assembler.Push(packet);
      ASSERT_TRUE(pushed.ok());
      frames += pushed->has_value();
    }
  }
  EXPECT_EQ(frames, 2);
  EXPECT_EQ(assembler.counters().completed, 2u);
  EXPECT_EQ(assembler.counters().incomplete, 1u);
}

TEST(Gvsp, LostTrailerOrLeaderIsCountedOnce) {
  const Block block = MakeBlock();
  GvspFrameAssembler assembler(1 << 16, 8, 64);
  auto first = Packets(block, 1);
  first.pop_back();  // trailer lost
  auto second = Packets(block, 2);
  second.erase(second.begin());  // leader lost
  auto third = Packets(block, 3);
  int frames = 0;
  for (const auto* packets : {&first, &second, &third}) {
    for (const auto& packet : *packets) {
      auto pushed = assembler.Push(packet);
      ASSERT_TRUE(pushed.ok());
      frames += pushed->has_value();
    }
  }
  EXPECT_EQ(frames, 1);
  EXPECT_EQ(assembler.counters().incomplete, 2u);
}

TEST(Gvsp, CorruptedPacketsReturnErrorsWithByteOffsetsAndDropTheBlock) {
  const Block block = MakeBlock();
  GvspFrameAssembler assembler(1 << 16, 8, 64);
  auto packets = Packets(block, 9);
  ASSERT_TRUE(assembler.Push(packets[0]).ok());
  // Part id beyond the leader's three parts.
  auto bad_part = packets[1];
  bad_part[8] = 5;
  auto pushed = assembler.Push(bad_part);
  ASSERT_FALSE(pushed.ok());
  EXPECT_NE(pushed.error().message.find("part 5"), std::string::npos) << pushed.error().message;
  EXPECT_NE(pushed.error().message.find("(byte 8)"), std::string::npos) << pushed.error().message;
  for (std::size_t i = 1; i < packets.size(); ++i) {
    auto result = assembler.Push(packets[i]);
    ASSERT_TRUE(result.ok());
    EXPECT_FALSE(result->has_value()) << "a block with a corrupted packet must not be returned";
  }
  EXPECT_EQ(assembler.counters().corrupted, 1u);

  // Offset past the end of the part.
  ASSERT_TRUE(assembler.Push(packets[0]).ok());
  auto bad_offset = packets[2];
  bad_offset[15] = 0xF0;
  pushed = assembler.Push(bad_offset);
  ASSERT_FALSE(pushed.ok());
  EXPECT_NE(pushed.error().message.find("exceed part"), std::string::npos)
      << pushed.error().message;
}

TEST(Gvsp, TruncatedAndOversizedInputsAreErrors) {
  const Block block = MakeBlock();
  const auto packets = Packets(block, 1);
  GvspFrameAssembler assembler(1 << 16, 8, 64);
  for (std::size_t size = 0; size < 8; ++size) {
    auto pushed = assembler.Push(std::span(packets[0]).first(size));
    ASSERT_FALSE(pushed.ok());
    EXPECT_NE(pushed.error().message.find("(byte " + std::to_string(size) + ")"),
              std::string::npos);
  }
  // A leader cut inside its part descriptions.
  auto pushed = assembler.Push(std::span(packets[0]).first(8 + 12 + 60));
  ASSERT_FALSE(pushed.ok());
  EXPECT_NE(pushed.error().message.find("declares 3 parts but has room for 1"), std::string::npos)
      << pushed.error().message;
  // A block larger than the reader's storage.
  GvspFrameAssembler small(256, 8, 64);
  pushed = small.Push(packets[0]);
  ASSERT_FALSE(pushed.ok());
  EXPECT_NE(pushed.error().message.find("more than the 256 bytes"), std::string::npos);
  // Unknown packet format.
  auto unknown = packets[1];
  unknown[4] = 0x09;
  EXPECT_FALSE(assembler.Push(unknown).ok());
}

TEST(Gvsp, ImagePayloadBlockAssemblesByPacketId) {
  GvspLeader leader;
  leader.payload_type = kGvspPayloadImage;
  GvspPartInfo info;
  info.pixel_format = pfnc::kCoord3dC32f;
  info.width = kWidth;
  info.height = kHeight;
  info.length = kWidth * kHeight * 4;
  leader.parts = {info};
  std::vector<float> depth(kWidth * kHeight);
  for (std::size_t i = 0; i < depth.size(); ++i) depth[i] = 800.0f + static_cast<float>(i);
  const auto bytes = FloatBytes(depth);
  const std::span<const std::uint8_t> parts[] = {bytes};
  const auto packets = PacketizeGvspBlock(5, leader, parts, 32);
  GvspFrameAssembler assembler(1 << 16, 8, 32);
  std::optional<GvspFrame> frame;
  for (const auto& packet : packets) {
    auto pushed = assembler.Push(packet);
    ASSERT_TRUE(pushed.ok()) << pushed.error().message;
    if (pushed->has_value()) frame = **pushed;
  }
  ASSERT_TRUE(frame.has_value());
  ASSERT_EQ(frame->parts.size(), 1u);
  EXPECT_TRUE(std::equal(bytes.begin(), bytes.end(), frame->parts[0].data.begin()));
}

}  // namespace
}  // namespace selfcal::camera

namespace selfcal::camera {
namespace {

// Multipart blocks with extended ids (how GigE Vision 2 cameras and our fake's multipart mode send
// them): the same block comes out, with its 64-bit block id; offsets count from the block start.
TEST(Gvsp, ExtendedIdMultipartBlocksReassemble) {
  const Block block = MakeBlock();
  GvspFrameAssembler assembler(4096, 4, 64);
  const std::uint64_t block_id = 0x1234567890ull;
  std::optional<GvspFrame> frame;
  const auto packets = Packets(block, 7);
  for (const auto& standard : packets) {
    const auto packet = ToExtendedIds(standard, block_id);
    auto header = DecodeGvspHeader(packet);
    ASSERT_TRUE(header.ok()) << header.error().message;
    EXPECT_TRUE(header->extended_ids);
    EXPECT_EQ(header->block_id, block_id);
    auto pushed = assembler.Push(packet);
    ASSERT_TRUE(pushed.ok()) << pushed.error().message;
    if (pushed->has_value()) frame = **pushed;
  }
  ASSERT_TRUE(frame.has_value());
  EXPECT_EQ(frame->block_id, block_id);
  ASSERT_EQ(frame->parts.size(), 3u);
  EXPECT_TRUE(std::equal(frame->parts[0].data.begin(), frame->parts[0].data.end(),
                         block.intensity.begin()));
  EXPECT_TRUE(
      std::equal(frame->parts[1].data.begin(), frame->parts[1].data.end(), block.range.begin()));
  EXPECT_TRUE(std::equal(frame->parts[2].data.begin(), frame->parts[2].data.end(),
                         block.confidence.begin()));

  // The second part's first packet says offset 0 (relative to the part): it lies in the first
  // part, an error that names the offset.
  std::size_t first_range_packet = 1 + (block.intensity.size() + 63) / 64;
  auto bad = packets[first_range_packet];
  for (int i = 10; i < 16; ++i)
    bad[static_cast<std::size_t>(i)] = 0;  // offset u48 after part id and zone
  ASSERT_TRUE(assembler.Push(packets[0]).ok());
  auto pushed = assembler.Push(bad);
  ASSERT_FALSE(pushed.ok());
  EXPECT_NE(pushed.error().message.find("lies before part 1"), std::string::npos)
      << pushed.error().message;
}

}  // namespace
}  // namespace selfcal::camera
