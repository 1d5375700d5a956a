// Strict reading of YAML files: every error names the file and the key path ("joints[2].upper"),
// unknown keys are errors, as libpointmatcher treats a key that is set but never used.
#pragma once

#include <yaml-cpp/yaml.h>

#include <functional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/util/expected.h"

namespace selfcal::yaml {

// Thrown inside readers, caught at the file boundary and turned into an Error.
class ParseError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A YAML mapping whose keys are checked off as they are read.
class StrictMap {
 public:
  StrictMap(const YAML::Node& node, std::string path, const std::string& file);

  // The value of a required key; ParseError naming file and key when missing or mistyped.
  template <typename T>
  T Required(const std::string& key) {
    return As<T>(Child(key, /*required=*/true), key);
  }
  template <typename T>
  T Optional(const std::string& key, const T& fallback) {
    const YAML::Node child = Child(key, /*required=*/false);
    return child ? As<T>(child, key) : fallback;
  }
  bool Has(const std::string& key) const;
  // A nested mapping or sequence, with its path for error messages.
  StrictMap Map(const std::string& key);
  std::vector<YAML::Node> Sequence(const std::string& key, bool required = true);
  // Marks a key as known without reading it (for sections other readers own).
  YAML::Node Raw(const std::string& key);

  // ParseError naming every key that was never read.
  void RejectUnknownKeys() const;

  std::string PathOf(const std::string& key) const;
  const std::string& file() const { return *file_; }

  [[noreturn]] void Fail(const std::string& key, const std::string& what) const;

 private:
  YAML::Node Child(const std::string& key, bool required);
  template <typename T>
  T As(const YAML::Node& node, const std::string& key) const {
    try {
      return node.as<T>();
    } catch (const YAML::Exception&) {
      Fail(key, "has the wrong type (line " + std::to_string(node.Mark().line + 1) + ")");
    }
  }

  YAML::Node node_;
  std::string path_;
  const std::string* file_;
  std::set<std::string> used_;
};

// Loads a file or a string; YAML syntax errors become ParseError with file, line and column.
YAML::Node LoadFile(const std::string& path);
YAML::Node LoadString(const std::string& text, const std::string& name);

// Runs `read` and converts ParseError and YAML exceptions into an Error.
template <typename T>
Expected<T> Catching(const std::function<T()>& read) {
  try {
    return read();
  } catch (const ParseError& e) {
    return Error{e.what()};
  } catch (const YAML::Exception& e) {
    return Error{e.what()};
  }
}

}  // namespace selfcal::yaml
