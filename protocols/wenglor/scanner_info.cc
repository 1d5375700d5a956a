#include "protocols/wenglor/scanner_info.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <string>

namespace selfcal::wenglor {
namespace {

struct Element {
  std::string_view text;
  std::size_t offset = 0;  // byte offset of the text in the document
};

// The text of the first <tag>...</tag>; an error when absent or unterminated.
Expected<Element> Find(std::string_view xml, const std::string& tag) {
  const std::string open = "<" + tag + ">";
  const std::string close = "</" + tag + ">";
  const std::size_t begin = xml.find(open);
  if (begin == std::string_view::npos) return Error{"info XML: element <" + tag + "> missing"};
  const std::size_t text_begin = begin + open.size();
  const std::size_t end = xml.find(close, text_begin);
  if (end == std::string_view::npos) {
    return Error{"info XML: element <" + tag + "> at byte " + std::to_string(begin) +
                 " is not closed"};
  }
  std::string_view text = xml.substr(text_begin, end - text_begin);
  while (!text.empty() && (text.front() == ' ' || text.front() == '\n' || text.front() == '\r' ||
                           text.front() == '\t')) {
    text.remove_prefix(1);
  }
  while (!text.empty() && (text.back() == ' ' || text.back() == '\n' || text.back() == '\r' ||
                           text.back() == '\t')) {
    text.remove_suffix(1);
  }
  return Element{text, text_begin};
}

struct NumberAt {
  double value = 0;
  std::size_t offset = 0;  // byte offset of the text in the document
};

Expected<NumberAt> Number(std::string_view xml, const std::string& tag) {
  auto element = Find(xml, tag);
  if (!element.ok()) return element.error();
  const std::string text(element->text);
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || errno != 0 || !std::isfinite(value)) {
    return Error{"info XML: <" + tag + "> at byte " + std::to_string(element->offset) +
                 " is not a number: '" + text.substr(0, 40) + "'"};
  }
  return NumberAt{value, element->offset};
}

bool IsSpace(char c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t'; }

// A truncated text still holds every field when it ends after the last one: the root element
// must close at the end of the document.
Status CheckRootClosed(std::string_view xml) {
  std::size_t at = 0;
  while (true) {
    while (at < xml.size() && IsSpace(xml[at])) ++at;
    if (xml.substr(at, 2) != "<?") break;
    const std::size_t end = xml.find("?>", at);
    if (end == std::string_view::npos) {
      return Error{"info XML: declaration at byte " + std::to_string(at) + " is not closed"};
    }
    at = end + 2;
  }
  std::size_t name_end = at + 1;
  while (name_end < xml.size() && xml[name_end] != '>' && xml[name_end] != '<' &&
         !IsSpace(xml[name_end])) {
    ++name_end;
  }
  if (at >= xml.size() || xml[at] != '<' || name_end == at + 1 || name_end >= xml.size()) {
    return Error{"info XML: no root element at byte " + std::to_string(at)};
  }
  const std::string close = "</" + std::string(xml.substr(at + 1, name_end - at - 1)) + ">";
  std::string_view rest = xml;
  while (!rest.empty() && IsSpace(rest.back())) rest.remove_suffix(1);
  if (!rest.ends_with(close)) {
    return Error{"info XML: root element at byte " + std::to_string(at) +
                 " is not closed at the end of the text (truncated?)"};
  }
  return OkStatus();
}

}  // namespace

Expected<ScannerInfo> ParseScannerInfo(std::string_view xml) {
  if (xml.size() > kMaxScannerInfoBytes) {
    return Error{"info XML of " + std::to_string(xml.size()) + " bytes exceeds the limit of " +
                 std::to_string(kMaxScannerInfoBytes)};
  }
  ScannerInfo info;
  auto order = Find(xml, "ordernumber");
  if (!order.ok()) return order.error();
  if (order->text.empty()) {
    return Error{"info XML: <ordernumber> at byte " + std::to_string(order->offset) + " is empty"};
  }
  info.order_number = std::string(order->text);
  if (auto serial = Find(xml, "serialnumber"); serial.ok()) {
    info.serial_number = std::string(serial->text);
  }
  constexpr double kMetresPerMillimetre = 1e-3;
  struct Field {
    const char* tag;
    double* value;
  };
  for (const Field& field : {Field{"workingrange_z_start", &info.working_range_z_start},
                             Field{"measuringrange_z", &info.measuring_range_z},
                             Field{"fieldwidth_x_start", &info.field_width_x_start},
                             Field{"fieldwidth_x_end", &info.field_width_x_end}}) {
    auto number = Number(xml, field.tag);
    if (!number.ok()) return number.error();
    if (number->value < 0) {
      return Error{std::string("info XML: <") + field.tag + "> at byte " +
                   std::to_string(number->offset) + " is negative"};
    }
    if (field.value == &info.measuring_range_z && number->value == 0) {
      return Error{"info XML: <measuringrange_z> at byte " + std::to_string(number->offset) +
                   " must be positive"};
    }
    *field.value = number->value * kMetresPerMillimetre;
  }
  auto pixels = Number(xml, "pixel_x_max");
  if (!pixels.ok()) return pixels.error();
  if (pixels->value < 1 || pixels->value > 65536 || std::floor(pixels->value) != pixels->value) {
    return Error{"info XML: <pixel_x_max> at byte " + std::to_string(pixels->offset) +
                 " must be a positive integer, got " + std::to_string(pixels->value)};
  }
  info.pixel_x_max = static_cast<int>(pixels->value);
  if (auto status = CheckRootClosed(xml); !status) return status.error();
  return info;
}

}  // namespace selfcal::wenglor
