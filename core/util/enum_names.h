// The names of an enum's values, written once as a table that printing and parsing both read, so
// that a value cannot be spelled one way in a file and another in a message.
//
//   inline constexpr EnumNames<SensorLayout, 3> kLayoutNames{{
//       {SensorLayout::kRotatingLidar, "rotating_lidar"},
//       {SensorLayout::kLineScanner, "line_scanner"},
//       {SensorLayout::kDepthCamera, "depth_camera"},
//   }};
//   kLayoutNames.Name(SensorLayout::kLineScanner)  // "line_scanner"
//   kLayoutNames.Parse("depth_camera")             // SensorLayout::kDepthCamera; nothing if
//   unknown kLayoutNames.Listed()                          // "rotating_lidar, line_scanner or
//   depth_camera"
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

namespace selfcal {

template <typename Enum, std::size_t N>
struct EnumNames {
  std::pair<Enum, const char*> entries[N];

  // The name of `value`; `unknown` for a value the table does not hold (a cast integer).
  constexpr const char* Name(Enum value, const char* unknown = "unknown") const {
    for (const auto& [entry, name] : entries) {
      if (entry == value) return name;
    }
    return unknown;
  }

  constexpr std::optional<Enum> Parse(std::string_view name) const {
    for (const auto& [entry, entry_name] : entries) {
      if (name == entry_name) return entry;
    }
    return std::nullopt;
  }

  // "a, b or c": the names in table order, for an error that says what is allowed.
  std::string Listed() const {
    std::string listed;
    for (std::size_t i = 0; i < N; ++i) {
      if (i > 0) listed += i + 1 == N ? " or " : ", ";
      listed += entries[i].second;
    }
    return listed;
  }
};

}  // namespace selfcal
