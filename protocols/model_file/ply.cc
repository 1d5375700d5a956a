#include "protocols/model_file/ply.h"

#include <bit>
#include <cstring>

#include "core/util/atomic_file.h"

namespace selfcal {
namespace {

static_assert(std::endian::native == std::endian::little, "PLY is written as the host's bytes");

template <typename T>
void Append(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

}  // namespace

std::string FormatPly(const std::vector<PlyPoint>& points, const std::string& comment) {
  std::string one_line = comment;
  for (char& c : one_line) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment " + one_line +
                    "\nelement vertex " + std::to_string(points.size()) +
                    "\nproperty float x\nproperty float y\nproperty float z\n"
                    "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                    "property int scan\nend_header\n";
  out.reserve(out.size() + points.size() * 19);
  for (const PlyPoint& p : points) {
    Append(out, p.x);
    Append(out, p.y);
    Append(out, p.z);
    Append(out, p.red);
    Append(out, p.green);
    Append(out, p.blue);
    Append(out, p.scan);
  }
  return out;
}

Status WritePlyFile(const std::string& path, const std::vector<PlyPoint>& points,
                    const std::string& comment) {
  return WriteFileAtomically(path, FormatPly(points, comment));
}

}  // namespace selfcal
