// The few pieces of JSON text the report writes: escaped strings, numbers that read back exactly
// (non-finite ones as null), and base64 of raw bytes for the clouds (HTML text:
// core/util/markup_text.h).
#pragma once

#include <string>
#include <string_view>

namespace selfcal::report {

std::string JsonString(std::string_view text);  // with the quotes; "</" written as "<\/"
std::string JsonNumber(double value);           // %.17g; NaN and infinities: null
std::string Base64(std::string_view bytes);

}  // namespace selfcal::report
