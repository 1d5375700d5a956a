#include "protocols/model_file/yaml_reader.h"

#include <cmath>
#include <map>

#include "core/util/atomic_file.h"

namespace selfcal::yaml {

StrictMap::StrictMap(const YAML::Node& node, std::string path, const std::string& file)
    : node_(node), path_(std::move(path)), file_(&file) {
  if (!node_.IsMap()) {
    throw ParseError(file + ": " + (path_.empty() ? std::string("document") : path_) +
                     " must be a mapping");
  }
  RejectRepeatedKeys();
}

// yaml-cpp keeps every entry of a mapping and a lookup finds the first, so a key given twice
// would silently drop the second value; YAML itself requires the keys of a mapping to be unique.
void StrictMap::RejectRepeatedKeys() const {
  std::map<std::string, int> first_line;
  for (const auto& entry : node_) {
    if (!entry.first.IsScalar()) continue;
    const int line = entry.first.Mark().line + 1;
    const auto [seen, inserted] = first_line.emplace(entry.first.Scalar(), line);
    if (!inserted) {
      throw ParseError(*file_ + ": key '" + PathOf(seen->first) + "' is given twice (lines " +
                       std::to_string(seen->second) + " and " + std::to_string(line) + ")");
    }
  }
}

std::string StrictMap::PathOf(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

void StrictMap::Fail(const std::string& key, const std::string& what) const {
  throw ParseError(*file_ + ": key '" + PathOf(key) + "' " + what);
}

double StrictMap::RequiredFinite(const std::string& key) {
  const double value = Required<double>(key);
  if (!std::isfinite(value)) Fail(key, "must be a finite number");
  return value;
}

double StrictMap::OptionalFinite(const std::string& key, double fallback) {
  const double value = Optional<double>(key, fallback);
  if (!std::isfinite(value)) Fail(key, "must be a finite number");
  return value;
}

bool StrictMap::Has(const std::string& key) const { return static_cast<bool>(node_[key]); }

YAML::Node StrictMap::Child(const std::string& key, bool required) {
  used_.insert(key);
  YAML::Node child = node_[key];
  if (!child && required) Fail(key, "is missing");
  if (child && child.IsNull() && required) Fail(key, "is empty");
  return child;
}

StrictMap StrictMap::Map(const std::string& key) {
  const YAML::Node child = Child(key, true);
  if (!child.IsMap()) Fail(key, "must be a mapping");
  return StrictMap(child, PathOf(key), *file_);
}

std::vector<YAML::Node> StrictMap::Sequence(const std::string& key, bool required) {
  const YAML::Node child = Child(key, required);
  if (!child) return {};
  if (!child.IsSequence()) Fail(key, "must be a sequence");
  return {child.begin(), child.end()};
}

YAML::Node StrictMap::Raw(const std::string& key) {
  used_.insert(key);
  return node_[key];
}

void StrictMap::RejectUnknownKeys() const {
  for (const auto& entry : node_) {
    const auto key = entry.first.as<std::string>();
    if (!used_.count(key)) {
      throw ParseError(*file_ + ": unknown key '" + PathOf(key) + "' (line " +
                       std::to_string(entry.first.Mark().line + 1) + ")");
    }
  }
}

namespace {

// yaml-cpp parses flow collections recursively: deep "[[[[..." input would exhaust the stack.
constexpr int kMaxFlowDepth = 64;
constexpr std::size_t kMaxYamlBytes = 4u << 20;

void CheckBounds(const std::string& text, const std::string& name) {
  if (text.size() > kMaxYamlBytes) {
    throw ParseError(name + ": " + std::to_string(text.size()) + " bytes, more than the " +
                     std::to_string(kMaxYamlBytes) + " a configuration file may have");
  }
  int depth = 0;
  int line = 1;
  for (const char c : text) {
    if (c == '\n') ++line;
    if (c == '[' || c == '{') ++depth;
    if (c == ']' || c == '}') --depth;
    if (depth > kMaxFlowDepth) {
      throw ParseError(name + ":" + std::to_string(line) + ": nesting deeper than " +
                       std::to_string(kMaxFlowDepth) + " levels");
    }
  }
}

}  // namespace

YAML::Node LoadString(const std::string& text, const std::string& name) {
  CheckBounds(text, name);
  try {
    return YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw ParseError(name + ":" + std::to_string(e.mark.line + 1) + ":" +
                     std::to_string(e.mark.column + 1) + ": YAML syntax error: " + e.msg);
  }
}

YAML::Node LoadFile(const std::string& path) {
  auto text = ReadFile(path);
  if (!text) throw ParseError(text.error().message);
  return LoadString(*text, path);
}

}  // namespace selfcal::yaml
