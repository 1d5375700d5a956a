#include "drivers/wenglor/scanner_info.h"

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

Expected<double> Number(std::string_view xml, const std::string& tag) {
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
  return value;
}

}  // namespace

Expected<ScannerInfo> ParseScannerInfo(std::string_view xml) {
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
    auto value = Number(xml, field.tag);
    if (!value.ok()) return value.error();
    if (*value < 0) {
      return Error{std::string("info XML: <") + field.tag + "> is negative"};
    }
    *field.value = *value * kMetresPerMillimetre;
  }
  auto pixels = Number(xml, "pixel_x_max");
  if (!pixels.ok()) return pixels.error();
  if (*pixels < 1 || *pixels > 65536 || std::floor(*pixels) != *pixels) {
    return Error{"info XML: <pixel_x_max> must be a positive integer, got " +
                 std::to_string(*pixels)};
  }
  info.pixel_x_max = static_cast<int>(*pixels);
  if (info.measuring_range_z <= 0) return Error{"info XML: <measuringrange_z> must be positive"};
  return info;
}

}  // namespace selfcal::wenglor
