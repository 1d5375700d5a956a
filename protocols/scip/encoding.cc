#include "protocols/scip/encoding.h"

namespace selfcal::scip {

char Checksum(std::string_view payload) {
  unsigned sum = 0;
  for (const char c : payload) sum += static_cast<unsigned char>(c);
  return static_cast<char>((sum & 0x3Fu) + 0x30u);
}

std::optional<std::uint32_t> DecodeValue(std::string_view chars) {
  if (chars.empty() || chars.size() > 4) return std::nullopt;
  std::uint32_t value = 0;
  for (const char c : chars) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x30 || u > 0x6F) return std::nullopt;
    value = (value << 6) | (u - 0x30u);
  }
  return value;
}

void AppendEncoded(std::string& out, std::uint32_t value, int width) {
  if (value > MaxEncodedValue(width)) value = MaxEncodedValue(width);
  for (int i = width - 1; i >= 0; --i) {
    out.push_back(static_cast<char>(((value >> (6 * i)) & 0x3Fu) + 0x30u));
  }
}

std::string EncodeValue(std::uint32_t value, int width) {
  std::string out;
  AppendEncoded(out, value, width);
  return out;
}

std::optional<int> DecodeDecimal(std::string_view digits) {
  if (digits.empty() || digits.size() > 9) return std::nullopt;
  int value = 0;
  for (const char c : digits) {
    if (c < '0' || c > '9') return std::nullopt;
    value = value * 10 + (c - '0');
  }
  return value;
}

}  // namespace selfcal::scip
