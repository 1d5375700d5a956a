// Decoding of 3D camera image parts (GenICam components: Range, Intensity, Confidence, coordinate
// maps) into an organized cloud in metres. Pure: no device, no allocation; the caller owns the
// output storage (the driver allocates it once at start).
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "core/util/enum_names.h"
#include "core/util/expected.h"

namespace selfcal::camera {

// What a part carries. GenICam cameras name components with ComponentSelector; a part whose
// component id is unknown is classified by its pixel format (ClassifyByPixelFormat).
enum class ComponentRole {
  kUnknown,
  kRange,
  kIntensity,
  kConfidence,
  kCoordinateMapA,
  kCoordinateMapB
};
// The roles' GenICam names (ComponentSelector entries): what cameras call them and errors say.
inline constexpr EnumNames<ComponentRole, 5> kComponentRoleNames{{
    {ComponentRole::kRange, "Range"},
    {ComponentRole::kIntensity, "Intensity"},
    {ComponentRole::kConfidence, "Confidence"},
    {ComponentRole::kCoordinateMapA, "CoordinateMapA"},
    {ComponentRole::kCoordinateMapB, "CoordinateMapB"},
}};

const char* ComponentRoleName(ComponentRole role);  // "unknown" for kUnknown
ComponentRole ClassifyByPixelFormat(std::uint32_t pixel_format);

// One image part of a buffer: a view of bytes owned by the transport (Aravis buffer, assembler).
struct ImagePart {
  ComponentRole role = ComponentRole::kUnknown;
  std::uint32_t pixel_format = 0;
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::uint32_t x_padding = 0;  // bytes after each line
  std::span<const std::uint8_t> data;
};

// Scan3d features for Coord3D_C32f output (Scan3dOutputMode = ProjectedC):
// x = z (a - u0) / f, y = z (b - v0) / (f * aspect), with (a, b) from the coordinate maps or,
// without maps, the pixel's column and row.
struct Scan3dParameters {
  double focal_length_px = 0.0;
  double principal_point_u_px = 0.0;
  double principal_point_v_px = 0.0;
  double aspect_ratio = 1.0;
};

struct DecodeOptions {
  double range_unit_m = 0.001;       // Range values are mm (PhotoNeo, SFNC default scale 1)
  std::uint32_t min_confidence = 1;  // Confidence below this marks a point invalid (NaN)
};

// Output storage, width * height floats each; intensity may be empty (not wanted).
struct CloudSpans {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::span<float> x, y, z, intensity;
};

struct DecodeSummary {
  std::uint32_t valid_points = 0;
  bool has_intensity = false;
};

// Writes the cloud of `parts` into `out`. Invalid points (zero or non-finite range, confidence
// below the threshold) become NaN in x, y and z. Errors name the part and the byte count.
Expected<DecodeSummary> DecodeOrganizedCloud(std::span<const ImagePart> parts,
                                             const Scan3dParameters& scan3d,
                                             const DecodeOptions& options, CloudSpans out);

}  // namespace selfcal::camera
