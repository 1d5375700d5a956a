#include "core/sim/obj_mesh.h"

#include <charconv>
#include <cmath>
#include <string_view>

#include "core/util/atomic_file.h"

namespace selfcal::sim {
namespace {

std::string_view NextToken(std::string_view& line) {
  std::size_t start = line.find_first_not_of(" \t\r");
  if (start == std::string_view::npos) {
    line = {};
    return {};
  }
  std::size_t end = line.find_first_of(" \t\r", start);
  if (end == std::string_view::npos) end = line.size();
  const std::string_view token = line.substr(start, end - start);
  line.remove_prefix(end);
  return token;
}

}  // namespace

Expected<TriangleMesh> ParseObjMesh(const std::string& text, const std::string& name) {
  TriangleMesh mesh;
  std::size_t line_number = 0;
  std::size_t position = 0;
  auto fail = [&](const std::string& what) {
    return Error{name + ":" + std::to_string(line_number) + ": " + what};
  };
  while (position < text.size()) {
    std::size_t end = text.find('\n', position);
    if (end == std::string::npos) end = text.size();
    std::string_view line(text.data() + position, end - position);
    position = end + 1;
    ++line_number;
    const std::string_view tag = NextToken(line);
    if (tag == "v") {
      Eigen::Vector3f v;
      for (int k = 0; k < 3; ++k) {
        const std::string_view token = NextToken(line);
        float value = 0;
        const auto result = std::from_chars(token.data(), token.data() + token.size(), value);
        if (token.empty() || result.ec != std::errc() || !std::isfinite(value)) {
          return fail("vertex coordinate " + std::to_string(k) + " is not a finite number");
        }
        v[k] = value;
      }
      mesh.vertices.push_back(v);
    } else if (tag == "f") {
      std::vector<int> face;
      for (std::string_view token = NextToken(line); !token.empty(); token = NextToken(line)) {
        const std::string_view index_text = token.substr(0, token.find('/'));
        long index = 0;
        const auto result =
            std::from_chars(index_text.data(), index_text.data() + index_text.size(), index);
        if (index_text.empty() || result.ec != std::errc() || index == 0) {
          return fail("face index '" + std::string(token) + "' is not a vertex index");
        }
        const long count = static_cast<long>(mesh.vertices.size());
        const long zero_based = index > 0 ? index - 1 : count + index;
        if (zero_based < 0 || zero_based >= count) {
          return fail("face index " + std::to_string(index) +
                      " refers to a vertex not defined yet (" + std::to_string(count) + " so far)");
        }
        face.push_back(static_cast<int>(zero_based));
      }
      if (face.size() < 3) return fail("face with fewer than 3 vertices");
      for (std::size_t k = 1; k + 1 < face.size(); ++k) {
        mesh.triangles.emplace_back(face[0], face[k], face[k + 1]);
      }
    }
  }
  if (mesh.triangles.empty()) return Error{name + ": no faces"};
  return mesh;
}

Expected<TriangleMesh> ReadObjMesh(const std::string& path) {
  auto text = ReadFile(path, 256u << 20);
  if (!text) return text.error();
  return ParseObjMesh(*text, path);
}

}  // namespace selfcal::sim
