#include "protocols/camera/cloud_decode.h"

#include <bit>
#include <cmath>
#include <limits>

#include "core/camera/pinhole_intrinsics.h"
#include "protocols/camera/pixel_format.h"

namespace selfcal::camera {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

std::string Describe(std::size_t index, const ImagePart& part) {
  return "part " + std::to_string(index) + " (" + ComponentRoleName(part.role) + ", " +
         PixelFormatName(part.pixel_format) + ", " + std::to_string(part.width) + "x" +
         std::to_string(part.height) + ")";
}

std::size_t LineBytes(const ImagePart& part) {
  return static_cast<std::size_t>(part.width) * BitsPerPixel(part.pixel_format) / 8 +
         part.x_padding;
}

// Checks that the part holds its lines and matches the cloud's size.
Status CheckPart(std::size_t index, const ImagePart& part, const CloudSpans& out) {
  if (part.width != out.width || part.height != out.height) {
    return Error{Describe(index, part) + ": size differs from the range part's " +
                 std::to_string(out.width) + "x" + std::to_string(out.height)};
  }
  const std::size_t needed = LineBytes(part) * part.height - (part.height > 0 ? part.x_padding : 0);
  if (part.data.size() < needed) {
    return Error{Describe(index, part) + ": " + std::to_string(part.data.size()) +
                 " bytes, expected " + std::to_string(needed) + " (data ends at byte offset " +
                 std::to_string(part.data.size()) + ")"};
  }
  return OkStatus();
}

// PFNC pixel data is little-endian whatever the host's byte order; read byte by byte, so that
// neither the order nor the alignment of the buffer matters.
std::uint16_t LoadU16(const std::uint8_t* bytes) {
  return static_cast<std::uint16_t>(bytes[0] | bytes[1] << 8);
}

float LoadF32(const std::uint8_t* bytes) {
  const std::uint32_t bits = std::uint32_t{bytes[0]} | std::uint32_t{bytes[1]} << 8 |
                             std::uint32_t{bytes[2]} << 16 | std::uint32_t{bytes[3]} << 24;
  return std::bit_cast<float>(bits);
}

float SampleAsFloat(const ImagePart& part, std::uint32_t row, std::uint32_t column) {
  const std::uint8_t* line = part.data.data() + LineBytes(part) * row;
  switch (BitsPerPixel(part.pixel_format)) {
    case 8:
      return static_cast<float>(line[column]);
    case 16:
      return static_cast<float>(LoadU16(line + 2 * column));
    default:
      return LoadF32(line + 4 * column);  // 32-bit formats are float32
  }
}

bool IsSupported(const ImagePart& part) {
  switch (part.role) {
    case ComponentRole::kRange:
      return part.pixel_format == pfnc::kCoord3dAbc32f || part.pixel_format == pfnc::kCoord3dC32f ||
             part.pixel_format == pfnc::kCoord3dC16;
    case ComponentRole::kIntensity:
      return part.pixel_format == pfnc::kMono8 || part.pixel_format == pfnc::kMono10 ||
             part.pixel_format == pfnc::kMono12 || part.pixel_format == pfnc::kMono16;
    case ComponentRole::kConfidence:
      return part.pixel_format == pfnc::kConfidence8 || part.pixel_format == pfnc::kConfidence16;
    case ComponentRole::kCoordinateMapA:
    case ComponentRole::kCoordinateMapB:
      return BitsPerPixel(part.pixel_format) == 32;
    case ComponentRole::kUnknown:
      return true;  // ignored
  }
  return false;
}

}  // namespace

const char* ComponentRoleName(ComponentRole role) { return kComponentRoleNames.Name(role); }

ComponentRole ClassifyByPixelFormat(std::uint32_t pixel_format) {
  switch (pixel_format) {
    case pfnc::kCoord3dAbc32f:
    case pfnc::kCoord3dC32f:
    case pfnc::kCoord3dC16:
      return ComponentRole::kRange;
    case pfnc::kCoord3dA32f:
      return ComponentRole::kCoordinateMapA;
    case pfnc::kCoord3dB32f:
      return ComponentRole::kCoordinateMapB;
    case pfnc::kConfidence8:
    case pfnc::kConfidence16:
      return ComponentRole::kConfidence;
    case pfnc::kMono8:
    case pfnc::kMono10:
    case pfnc::kMono12:
    case pfnc::kMono16:
      return ComponentRole::kIntensity;
    default:
      return ComponentRole::kUnknown;
  }
}

namespace {

// The components of one buffer by role; range is always present.
struct Components {
  const ImagePart* range = nullptr;
  const ImagePart* intensity = nullptr;
  const ImagePart* confidence = nullptr;
  const ImagePart* map_a = nullptr;
  const ImagePart* map_b = nullptr;
};

// Sorts `parts` by role, each checked against the output size; an error names the part.
Expected<Components> SortComponents(std::span<const ImagePart> parts, const CloudSpans& out) {
  Components c;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const ImagePart& part = parts[i];
    if (!IsSupported(part)) {
      return Error{Describe(i, part) + ": pixel format not supported for this component"};
    }
    const ImagePart** slot = nullptr;
    switch (part.role) {
      case ComponentRole::kRange:
        slot = &c.range;
        break;
      case ComponentRole::kIntensity:
        slot = &c.intensity;
        break;
      case ComponentRole::kConfidence:
        slot = &c.confidence;
        break;
      case ComponentRole::kCoordinateMapA:
        slot = &c.map_a;
        break;
      case ComponentRole::kCoordinateMapB:
        slot = &c.map_b;
        break;
      case ComponentRole::kUnknown:
        continue;
    }
    if (*slot != nullptr) return Error{Describe(i, part) + ": component appears twice"};
    if (auto status = CheckPart(i, part, out); !status) return status.error();
    *slot = &part;
  }
  if (c.range == nullptr)
    return Error{"buffer has no Range part (" + std::to_string(parts.size()) + " parts)"};
  if ((c.map_a == nullptr) != (c.map_b == nullptr)) {
    return Error{"coordinate maps come in pairs: only one of CoordinateMapA/B is present"};
  }
  return c;
}

}  // namespace

Expected<DecodeSummary> DecodeOrganizedCloud(std::span<const ImagePart> parts,
                                             const Scan3dParameters& scan3d,
                                             const DecodeOptions& options, CloudSpans out) {
  const std::size_t count = static_cast<std::size_t>(out.width) * out.height;
  // Refused before the row loop, which would otherwise walk up to 2^32 empty rows.
  if (count == 0) {
    return Error{"the image is " + std::to_string(out.width) + "x" + std::to_string(out.height) +
                 ": no pixels"};
  }
  if (out.x.size() < count || out.y.size() < count || out.z.size() < count ||
      (!out.intensity.empty() && out.intensity.size() < count)) {
    return Error{"output storage holds fewer than " + std::to_string(count) + " points"};
  }
  auto components = SortComponents(parts, out);
  if (!components) return components.error();
  const auto [range, intensity, confidence, map_a, map_b] = *components;
  const bool projected = range->pixel_format != pfnc::kCoord3dAbc32f;
  if (projected && !(scan3d.focal_length_px > 0.0 && scan3d.aspect_ratio > 0.0)) {
    return Error{"Range is " + PixelFormatName(range->pixel_format) +
                 " (ProjectedC) but Scan3dFocalLength/Scan3dAspectRatio are not positive"};
  }

  const auto unit = static_cast<float>(options.range_unit_m);
  const PinholeIntrinsics k{scan3d.focal_length_px, scan3d.focal_length_px * scan3d.aspect_ratio,
                            scan3d.principal_point_u_px, scan3d.principal_point_v_px};
  const std::size_t range_line = LineBytes(*range);
  DecodeSummary summary;
  for (std::uint32_t row = 0; row < out.height; ++row) {
    const std::uint8_t* line = range->data.data() + range_line * row;
    for (std::uint32_t column = 0; column < out.width; ++column) {
      const std::size_t index = static_cast<std::size_t>(row) * out.width + column;
      float x, y, z;
      if (!projected) {
        x = LoadF32(line + 12 * column) * unit;
        y = LoadF32(line + 12 * column + 4) * unit;
        z = LoadF32(line + 12 * column + 8) * unit;
      } else {
        z = SampleAsFloat(*range, row, column) * unit;
        const double a = map_a ? SampleAsFloat(*map_a, row, column) : static_cast<double>(column);
        const double b = map_b ? SampleAsFloat(*map_b, row, column) : static_cast<double>(row);
        const Eigen::Vector3d p = k.Unproject(a, b, z);
        x = static_cast<float>(p.x());
        y = static_cast<float>(p.y());
      }
      bool valid = std::isfinite(x) && std::isfinite(y) && std::isfinite(z) && z != 0.0f;
      if (valid && confidence != nullptr) {
        valid =
            SampleAsFloat(*confidence, row, column) >= static_cast<float>(options.min_confidence);
      }
      if (valid) {
        out.x[index] = x;
        out.y[index] = y;
        out.z[index] = z;
        ++summary.valid_points;
      } else {
        out.x[index] = out.y[index] = out.z[index] = kNaN;
      }
      if (!out.intensity.empty()) {
        out.intensity[index] = intensity ? SampleAsFloat(*intensity, row, column) : 0.0f;
      }
    }
  }
  summary.has_intensity = intensity != nullptr && !out.intensity.empty();
  return summary;
}

}  // namespace selfcal::camera
