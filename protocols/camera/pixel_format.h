// GenICam PFNC pixel format codes used by depth cameras (the values of arvenums.h and the PFNC
// standard), and the size of a pixel, which PFNC encodes in bits 16..23 of the code.
#pragma once

#include <cstdint>
#include <string>

namespace selfcal::camera {

namespace pfnc {
inline constexpr std::uint32_t kMono8 = 0x01080001;
inline constexpr std::uint32_t kMono10 = 0x01100003;  // 10 bits in 16
inline constexpr std::uint32_t kMono12 = 0x01100005;  // 12 bits in 16
inline constexpr std::uint32_t kMono16 = 0x01100007;
inline constexpr std::uint32_t kCoord3dAbc32f = 0x026000C0;  // x, y, z float32 interleaved
inline constexpr std::uint32_t kCoord3dA32f = 0x012000BD;    // coordinate map A (x)
inline constexpr std::uint32_t kCoord3dB32f = 0x012000BE;    // coordinate map B (y)
inline constexpr std::uint32_t kCoord3dC32f = 0x012000BF;    // depth only
inline constexpr std::uint32_t kCoord3dC16 = 0x011000B8;
inline constexpr std::uint32_t kConfidence8 = 0x010800C6;
inline constexpr std::uint32_t kConfidence16 = 0x011000C7;
}  // namespace pfnc

// Bits per pixel as PFNC encodes them in the code itself.
constexpr std::uint32_t BitsPerPixel(std::uint32_t pixel_format) {
  return (pixel_format >> 16) & 0xFF;
}

// A readable name for error messages ("Coord3D_ABC32f", or the hex code).
std::string PixelFormatName(std::uint32_t pixel_format);

}  // namespace selfcal::camera
