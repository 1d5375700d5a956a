// Strict reading of YAML files: every error names the file and the key path ("joints[2].upper"),
// unknown keys are errors, as libpointmatcher treats a key that is set but never used, and so is
// a key given twice in one mapping.
#pragma once

#include <yaml-cpp/yaml.h>

#include <functional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/util/enum_names.h"
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
  // The value of a key that names one of `names`; ParseError "must be a, b or c, not 'd'".
  template <typename Enum, std::size_t N>
  Enum RequiredChoice(const std::string& key, const EnumNames<Enum, N>& names) {
    return Choose(key, Required<std::string>(key), names);
  }
  template <typename Enum, std::size_t N>
  Enum OptionalChoice(const std::string& key, Enum fallback, const EnumNames<Enum, N>& names) {
    return Choose(key, Optional<std::string>(key, names.Name(fallback)), names);
  }
  // A number that is neither .inf nor .nan (no writer writes those back as a number);
  // ParseError "must be a finite number".
  double RequiredFinite(const std::string& key);
  double OptionalFinite(const std::string& key, double fallback);
  bool Has(const std::string& key) const;
  // A nested mapping or sequence, with its path for error messages.
  StrictMap Map(const std::string& key);
  // An optional section: when `key` is there, `read(section)` takes its keys and any other key
  // in it is an error; when it is not, nothing happens.
  template <typename Read>
  void OptionalSection(const std::string& key, Read read) {
    if (!Has(key)) return;
    StrictMap section = Map(key);
    read(section);
    section.RejectUnknownKeys();
  }
  std::vector<YAML::Node> Sequence(const std::string& key, bool required = true);
  // Marks a key as known without reading it (for sections other readers own).
  YAML::Node Raw(const std::string& key);

  // ParseError naming every key that was never read.
  void RejectUnknownKeys() const;

  std::string PathOf(const std::string& key) const;
  const std::string& file() const { return *file_; }

  [[noreturn]] void Fail(const std::string& key, const std::string& what) const;

 private:
  void RejectRepeatedKeys() const;
  YAML::Node Child(const std::string& key, bool required);
  template <typename Enum, std::size_t N>
  Enum Choose(const std::string& key, const std::string& name, const EnumNames<Enum, N>& names) {
    if (const auto value = names.Parse(name)) return *value;
    Fail(key, "must be " + names.Listed() + ", not '" + name + "'");
  }
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

// A whole document read by `read(map)` from its top-level mapping `map` (map.file() is `name`): a
// key that `read` left unread is an error once it returns, so every document is as strict as its
// reader.
template <typename T, typename Read>
T ReadTopLevel(const YAML::Node& root, const std::string& name, Read read) {
  StrictMap map(root, "", name);
  T document = read(map);
  map.RejectUnknownKeys();
  return document;
}

// The same from the file `path` or from `text` (named `name` in errors): syntax errors,
// ParseError and YAML exceptions all come back as an Error.
template <typename T, typename Read>
Expected<T> ReadDocumentFile(const std::string& path, Read read) {
  return Catching<T>([&] { return ReadTopLevel<T>(LoadFile(path), path, read); });
}
template <typename T, typename Read>
Expected<T> ParseDocument(const std::string& text, const std::string& name, Read read) {
  return Catching<T>([&] { return ReadTopLevel<T>(LoadString(text, name), name, read); });
}

}  // namespace selfcal::yaml
