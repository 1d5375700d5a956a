#include "protocols/model_file/yaml_writer.h"

#include <yaml-cpp/yaml.h>

#include <cstdio>

namespace selfcal::yaml {

std::string Number(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  return buffer;
}

std::string NumberList(const std::vector<double>& values) {
  std::string out = "[";
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i) out += ", ";
    out += Number(values[i]);
  }
  return out + "]";
}

namespace {

bool PlainIsSafe(std::string_view text) {
  if (text.empty() || text == "null" || text == "Null" || text == "NULL") return false;
  const auto word = [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '.' || c == '/';
  };
  if (!word(text.front())) return false;  // no leading '-', '+' (indicators, signs)
  for (const char c : text) {
    if (!word(c) && c != '-' && c != '+') return false;
  }
  return true;
}

}  // namespace

std::string Text(std::string_view text) {
  if (PlainIsSafe(text)) return std::string(text);
  YAML::Emitter out;
  out << YAML::DoubleQuoted << std::string(text);
  return out.c_str();
}

}  // namespace selfcal::yaml
