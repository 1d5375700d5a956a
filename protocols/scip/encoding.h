// SCIP 2.0 character encoding and checksums (protocols.md 1.2, 1.3).
// Each character carries 6 bits (c - 0x30), most significant first; a line's checksum is the
// sum of its payload bytes, lower 6 bits, plus 0x30.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace selfcal::scip {

// Largest value `width` characters can carry (2: 4095, 3: 262143, 4: 16777215).
constexpr std::uint32_t MaxEncodedValue(int width) {
  return width >= 4 ? 0xFFFFFFu : ((1u << (6 * width)) - 1u);
}

// The checksum character of `payload`.
char Checksum(std::string_view payload);

// Decodes 1..4 characters; nullopt when a character is outside '0'..'o' (0x30..0x6F).
std::optional<std::uint32_t> DecodeValue(std::string_view chars);

// Appends `value` in `width` characters (width 1..4). Values above MaxEncodedValue(width) are
// clamped: the encoder never writes a character outside the alphabet.
void AppendEncoded(std::string& out, std::uint32_t value, int width);
std::string EncodeValue(std::uint32_t value, int width);

// A decimal field (command parameters, status codes, PP values) of 1 to 9 digits; nullopt for
// anything else.
std::optional<int> DecodeDecimal(std::string_view digits);

}  // namespace selfcal::scip
