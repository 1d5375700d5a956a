// Point clouds as PLY (binary little endian 1.0), the format CloudCompare and MeshLab open:
// x, y, z as float [m], red, green, blue as uchar, and the recording's scan_index as int (a
// scalar field in CloudCompare, ignored by MeshLab).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/util/expected.h"

namespace selfcal {

struct PlyPoint {
  float x = 0, y = 0, z = 0;  // m
  std::uint8_t red = 0, green = 0, blue = 0;
  std::int32_t scan = 0;
};

// The whole file; `comment` (one line, no newline) goes into the header.
std::string FormatPly(const std::vector<PlyPoint>& points, const std::string& comment);

// FormatPly, written atomically.
Status WritePlyFile(const std::string& path, const std::vector<PlyPoint>& points,
                    const std::string& comment);

}  // namespace selfcal
