// Any bytes as a stream of GVSP packets (each a 2-byte big-endian length and its bytes) into the
// frame assembler and every assembled frame into the organized-cloud decoder: an error or a frame
// whose parts hold exactly the bytes their leader declared; never a crash or a read beyond a
// packet. The first byte picks the assembler's image packet size and whether ids are extended.
#include <cstdint>
#include <span>
#include <vector>

#include "protocols/camera/cloud_decode.h"
#include "protocols/camera/gvsp.h"

namespace {

using namespace selfcal::camera;

constexpr std::size_t kMaxPayload = 1 << 16;
constexpr std::size_t kMaxParts = 4;
constexpr std::size_t kMaxPoints = 1 << 14;

void DecodeFrame(const GvspFrame& frame) {
  std::vector<ImagePart> parts;
  std::uint32_t width = 0, height = 0;
  for (const GvspAssembledPart& part : frame.parts) {
    if (part.data.size() != part.info.length) __builtin_trap();  // never a short part
    ImagePart image;
    image.role = ClassifyByPixelFormat(part.info.pixel_format);
    image.pixel_format = part.info.pixel_format;
    image.width = part.info.width;
    image.height = part.info.height;
    image.x_padding = part.info.x_padding;
    image.data = part.data;
    parts.push_back(image);
    if (image.role == ComponentRole::kRange) {
      width = image.width;
      height = image.height;
    }
  }
  if (std::uint64_t{width} * height > kMaxPoints) return;
  static std::vector<float> x(kMaxPoints), y(kMaxPoints), z(kMaxPoints), intensity(kMaxPoints);
  const std::size_t n = std::size_t{width} * height;
  const CloudSpans out{width,
                       height,
                       std::span(x).first(n),
                       std::span(y).first(n),
                       std::span(z).first(n),
                       std::span(intensity).first(n)};
  Scan3dParameters scan3d;
  scan3d.focal_length_px = 500;
  (void)DecodeOrganizedCloud(parts, scan3d, {}, out);
  (void)DecodeOrganizedCloud(parts, {}, {}, out);  // no Scan3d: focal length 0 must be refused
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::size_t image_block_bytes = 1 + (data[0] & 0x7F) * 8;
  const bool extended = (data[0] & 0x80) != 0;
  GvspFrameAssembler assembler(kMaxPayload, kMaxParts, image_block_bytes);
  std::size_t at = 1;
  while (at + 2 <= size) {
    const std::size_t length = std::size_t{data[at]} << 8 | data[at + 1];
    at += 2;
    const std::span<const std::uint8_t> packet(data + at, std::min(length, size - at));
    at += packet.size();
    // A copy of exactly the packet's size, so ASan sees any read beyond it.
    std::vector<std::uint8_t> bytes = extended
                                          ? ToExtendedIds(packet, 1)
                                          : std::vector<std::uint8_t>(packet.begin(), packet.end());
    if (auto header = DecodeGvspHeader(bytes); header.ok()) {
      GvspLeader leader;
      leader.parts.reserve(kMaxParts);
      (void)DecodeGvspLeader(bytes, *header, leader);
    }
    auto pushed = assembler.Push(bytes);
    if (pushed.ok() && pushed->has_value()) DecodeFrame(**pushed);
  }
  const GvspCounters& counters = assembler.counters();
  (void)counters;
  return 0;
}
