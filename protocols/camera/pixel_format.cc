#include "protocols/camera/pixel_format.h"

#include <cstdio>

namespace selfcal::camera {

std::string PixelFormatName(std::uint32_t pixel_format) {
  switch (pixel_format) {
    case pfnc::kMono8:
      return "Mono8";
    case pfnc::kMono10:
      return "Mono10";
    case pfnc::kMono12:
      return "Mono12";
    case pfnc::kMono16:
      return "Mono16";
    case pfnc::kCoord3dAbc32f:
      return "Coord3D_ABC32f";
    case pfnc::kCoord3dA32f:
      return "Coord3D_A32f";
    case pfnc::kCoord3dB32f:
      return "Coord3D_B32f";
    case pfnc::kCoord3dC32f:
      return "Coord3D_C32f";
    case pfnc::kCoord3dC16:
      return "Coord3D_C16";
    case pfnc::kConfidence8:
      return "Confidence8";
    case pfnc::kConfidence16:
      return "Confidence16";
    default:
      break;
  }
  char text[16];
  std::snprintf(text, sizeof(text), "0x%08X", pixel_format);
  return text;
}

}  // namespace selfcal::camera
