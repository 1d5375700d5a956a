#include "protocols/camera/cloud_decode.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "protocols/camera/pixel_format.h"

namespace selfcal::camera {
namespace {

template <typename T>
std::vector<std::uint8_t> Bytes(const std::vector<T>& values) {
  std::vector<std::uint8_t> bytes(values.size() * sizeof(T));
  std::memcpy(bytes.data(), values.data(), bytes.size());
  return bytes;
}

ImagePart Part(ComponentRole role, std::uint32_t format, std::uint32_t w, std::uint32_t h,
               std::span<const std::uint8_t> data) {
  return ImagePart{role, format, w, h, 0, data};
}

TEST(CloudDecode, ProjectedCWithoutMapsUsesPixelCoordinatesAndScan3dIntrinsics) {
  const std::uint32_t w = 4, h = 3;
  std::vector<float> depth_mm(w * h, 1000.0f);
  depth_mm[5] = 0.0f;           // no measurement
  depth_mm[6] = std::nanf("");  // no measurement
  const auto bytes = Bytes(depth_mm);
  const ImagePart parts[] = {Part(ComponentRole::kRange, pfnc::kCoord3dC32f, w, h, bytes)};
  Scan3dParameters scan3d{100.0, 1.5, 1.0, 2.0};
  std::vector<float> x(w * h), y(w * h), z(w * h);
  auto summary = DecodeOrganizedCloud(parts, scan3d, {}, {w, h, x, y, z, {}});
  ASSERT_TRUE(summary.ok()) << summary.error().message;
  EXPECT_EQ(summary->valid_points, w * h - 2);
  EXPECT_FALSE(summary->has_intensity);
  // Pixel (row 2, column 3): x = 1 m * (3 - 1.5) / 100, y = 1 m * (2 - 1) / (100 * 2).
  EXPECT_NEAR(x[11], 0.015, 1e-7);
  EXPECT_NEAR(y[11], 0.005, 1e-7);
  EXPECT_NEAR(z[11], 1.0, 1e-7);
  EXPECT_TRUE(std::isnan(z[5]) && std::isnan(x[5]));
  EXPECT_TRUE(std::isnan(z[6]) && std::isnan(y[6]));
}

// Golden bytes: PFNC data is little-endian on any host, and a part may start at any address (a
// GVSP payload offset is not a multiple of 4).
TEST(CloudDecode, PixelDataIsLittleEndianAtAnyAlignment) {
  const std::vector<std::uint8_t> c16 = {0xAA, 0xE8, 0x03, 0x02, 0x01};  // 1000, 258 mm
  const ImagePart projected[] = {
      Part(ComponentRole::kRange, pfnc::kCoord3dC16, 2, 1, std::span(c16).subspan(1))};
  std::vector<float> x(2), y(2), z(2);
  auto summary = DecodeOrganizedCloud(projected, {100.0, 0.0, 0.0, 1.0}, {}, {2, 1, x, y, z, {}});
  ASSERT_TRUE(summary.ok()) << summary.error().message;
  EXPECT_FLOAT_EQ(z[0], 1.0f);
  EXPECT_FLOAT_EQ(z[1], 0.258f);

  // 1.0f, -2.0f, 1000.0f as Coord3D_ABC32f, after 3 bytes.
  const std::vector<std::uint8_t> abc = {0x11, 0x22, 0x33, 0x00, 0x00, 0x80, 0x3F, 0x00,
                                         0x00, 0x00, 0xC0, 0x00, 0x00, 0x7A, 0x44};
  const ImagePart points[] = {
      Part(ComponentRole::kRange, pfnc::kCoord3dAbc32f, 1, 1, std::span(abc).subspan(3))};
  summary = DecodeOrganizedCloud(points, {}, {}, {1, 1, x, y, z, {}});
  ASSERT_TRUE(summary.ok()) << summary.error().message;
  EXPECT_FLOAT_EQ(x[0], 0.001f);
  EXPECT_FLOAT_EQ(y[0], -0.002f);
  EXPECT_FLOAT_EQ(z[0], 1.0f);
}

TEST(CloudDecode, CoordinateMapsReplacePixelCoordinates) {
  const std::uint32_t w = 2, h = 2;
  const auto range = Bytes(std::vector<float>{500, 500, 500, 500});
  const auto map_a = Bytes(std::vector<float>{10, 20, 30, 40});
  const auto map_b = Bytes(std::vector<float>{-10, -20, -30, -40});
  const ImagePart parts[] = {Part(ComponentRole::kRange, pfnc::kCoord3dC32f, w, h, range),
                             Part(ComponentRole::kCoordinateMapA, pfnc::kCoord3dA32f, w, h, map_a),
                             Part(ComponentRole::kCoordinateMapB, pfnc::kCoord3dB32f, w, h, map_b)};
  std::vector<float> x(4), y(4), z(4);
  auto summary = DecodeOrganizedCloud(parts, {50.0, 0.0, 0.0, 1.0}, {}, {w, h, x, y, z, {}});
  ASSERT_TRUE(summary.ok()) << summary.error().message;
  EXPECT_NEAR(x[3], 0.5 * 40 / 50, 1e-6);
  EXPECT_NEAR(y[2], 0.5 * -30 / 50, 1e-6);
  // One map alone is an error.
  const ImagePart half[] = {parts[0], parts[1]};
  EXPECT_FALSE(DecodeOrganizedCloud(half, {50.0, 0.0, 0.0, 1.0}, {}, {w, h, x, y, z, {}}).ok());
}

TEST(CloudDecode, ConfidenceThresholdAndPaddingAreHonoured) {
  const std::uint32_t w = 2, h = 2;
  // Range with 4 bytes of padding after each line.
  std::vector<float> padded = {1, 2, 300, 4, 5, 600, -1, /*pad*/ 7, 8, 900, 10, 11, 1200, -1};
  const auto range = Bytes(padded);
  const std::vector<std::uint8_t> confidence = {255, 9, 10, 200};
  ImagePart range_part = Part(ComponentRole::kRange, pfnc::kCoord3dAbc32f, w, h, range);
  range_part.x_padding = 4;
  const ImagePart parts[] = {
      range_part, Part(ComponentRole::kConfidence, pfnc::kConfidence8, w, h, confidence)};
  std::vector<float> x(4), y(4), z(4);
  DecodeOptions options;
  options.min_confidence = 10;
  auto summary = DecodeOrganizedCloud(parts, {}, options, {w, h, x, y, z, {}});
  ASSERT_TRUE(summary.ok()) << summary.error().message;
  EXPECT_EQ(summary->valid_points, 3u);
  EXPECT_TRUE(std::isnan(z[1]));
  EXPECT_NEAR(z[2], 0.9, 1e-6);
  EXPECT_NEAR(x[3], 0.010, 1e-7);
  EXPECT_NEAR(z[3], 1.2, 1e-6);
}

TEST(CloudDecode, BadPartsAreErrorsThatNameThePart) {
  const std::uint32_t w = 3, h = 2;
  const auto short_range = Bytes(std::vector<float>(w * h * 3 - 1, 1.0f));
  std::vector<float> x(6), y(6), z(6);
  const ImagePart truncated[] = {
      Part(ComponentRole::kRange, pfnc::kCoord3dAbc32f, w, h, short_range)};
  auto result = DecodeOrganizedCloud(truncated, {}, {}, {w, h, x, y, z, {}});
  ASSERT_FALSE(result.ok());
  EXPECT_NE(
      result.error().message.find("part 0 (Range, Coord3D_ABC32f, 3x2): 68 bytes, expected 72"),
      std::string::npos)
      << result.error().message;

  const auto range = Bytes(std::vector<float>(w * h * 3, 1.0f));
  const std::vector<std::uint8_t> confidence(4, 255);
  const ImagePart wrong_size[] = {
      Part(ComponentRole::kRange, pfnc::kCoord3dAbc32f, w, h, range),
      Part(ComponentRole::kConfidence, pfnc::kConfidence8, 2, 2, confidence)};
  result = DecodeOrganizedCloud(wrong_size, {}, {}, {w, h, x, y, z, {}});
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.error().message.find("size differs"), std::string::npos);

  const ImagePart no_range[] = {Part(ComponentRole::kConfidence, pfnc::kConfidence8, w, h, range)};
  EXPECT_FALSE(DecodeOrganizedCloud(no_range, {}, {}, {w, h, x, y, z, {}}).ok());

  const ImagePart wrong_format[] = {Part(ComponentRole::kRange, pfnc::kMono8, w, h, range)};
  EXPECT_FALSE(DecodeOrganizedCloud(wrong_format, {}, {}, {w, h, x, y, z, {}}).ok());

  // ProjectedC needs a focal length.
  const ImagePart projected[] = {Part(ComponentRole::kRange, pfnc::kCoord3dC32f, w, h, range)};
  result = DecodeOrganizedCloud(projected, {}, {}, {w, h, x, y, z, {}});
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.error().message.find("Scan3dFocalLength"), std::string::npos);

  // Too little output storage.
  std::vector<float> small(5);
  EXPECT_FALSE(DecodeOrganizedCloud(projected, {10, 0, 0, 1}, {}, {w, h, small, y, z, {}}).ok());
}

// An image without pixels is refused at once: found by fuzz_gvsp, a 263-byte GVSP stream whose
// Range part was 0 pixels wide and 4 billion rows high kept the decoder looping over the empty
// rows for minutes (a camera driver stalled by one leader).
TEST(CloudDecode, AnImageWithoutPixelsIsRefusedAtOnce) {
  const std::vector<std::uint8_t> nothing;
  std::vector<float> x, y, z;
  for (const auto& [w, h] : {std::pair<std::uint32_t, std::uint32_t>{0, 1u << 20}, {1u << 20, 0}}) {
    const ImagePart empty[] = {Part(ComponentRole::kRange, pfnc::kCoord3dAbc32f, w, h, nothing)};
    auto result = DecodeOrganizedCloud(empty, {}, {}, {w, h, x, y, z, {}});
    ASSERT_FALSE(result.ok()) << w << "x" << h;
    EXPECT_NE(result.error().message.find("no pixels"), std::string::npos)
        << result.error().message;
  }
}

TEST(CloudDecode, ClassifiesComponentsByPixelFormat) {
  EXPECT_EQ(ClassifyByPixelFormat(pfnc::kCoord3dAbc32f), ComponentRole::kRange);
  EXPECT_EQ(ClassifyByPixelFormat(pfnc::kCoord3dC32f), ComponentRole::kRange);
  EXPECT_EQ(ClassifyByPixelFormat(pfnc::kCoord3dA32f), ComponentRole::kCoordinateMapA);
  EXPECT_EQ(ClassifyByPixelFormat(pfnc::kCoord3dB32f), ComponentRole::kCoordinateMapB);
  EXPECT_EQ(ClassifyByPixelFormat(pfnc::kConfidence8), ComponentRole::kConfidence);
  EXPECT_EQ(ClassifyByPixelFormat(pfnc::kMono16), ComponentRole::kIntensity);
  EXPECT_EQ(ClassifyByPixelFormat(0x02180014), ComponentRole::kUnknown);  // RGB8
  EXPECT_EQ(BitsPerPixel(pfnc::kCoord3dAbc32f), 96u);
}

}  // namespace
}  // namespace selfcal::camera
