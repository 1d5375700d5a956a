// For tests of a program's configuration echo (program::Program::Setting): the key path of every
// value a YAML file sets, spelled as the echo spells it ("sync.period", "joints[2].node").
#pragma once

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <string>
#include <vector>

namespace selfcal::testing {

inline void AppendLeafPaths(const YAML::Node& node, const std::string& path,
                            std::vector<std::string>& out) {
  if (node.IsMap()) {
    for (const auto& item : node) {
      const std::string key = item.first.as<std::string>();
      AppendLeafPaths(item.second, path.empty() ? key : path + "." + key, out);
    }
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) {
      AppendLeafPaths(node[i], path + "[" + std::to_string(i) + "]", out);
    }
  } else {
    out.push_back(path);
  }
}

inline std::vector<std::string> LeafPaths(const YAML::Node& root) {
  std::vector<std::string> out;
  AppendLeafPaths(root, "", out);
  return out;
}

// The keys of `configuration` ("key=value key=value ..."), in order.
inline std::vector<std::string> EchoedKeys(const std::string& configuration) {
  std::vector<std::string> keys;
  std::size_t begin = 0;
  while (begin < configuration.size()) {
    const std::size_t end = std::min(configuration.find(' ', begin), configuration.size());
    const std::string item = configuration.substr(begin, end - begin);
    keys.push_back(item.substr(0, item.find('=')));
    begin = end + 1;
  }
  return keys;
}

// The value `configuration` ("key=value key=value ...") echoes for `key`, or "(missing)".
inline std::string EchoedValue(const std::string& configuration, const std::string& key) {
  const std::string text = " " + configuration + " ";
  const std::size_t at = text.find(" " + key + "=");
  if (at == std::string::npos) return "(missing)";
  const std::size_t begin = at + key.size() + 2;
  return text.substr(begin, text.find(' ', begin) - begin);
}

}  // namespace selfcal::testing
