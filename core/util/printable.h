// Text from outside (a request's fields, a device's reply) made safe for a log line: control
// characters, DEL and bytes outside printable ASCII become \xNN (a newline cannot forge a second
// log line, an escape sequence cannot rewrite the terminal), and long text is cut.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace selfcal {

// At most `max_chars` characters of `text`, escaped; a cut text ends in "...(N bytes)".
std::string Printable(std::string_view text, std::size_t max_chars = 64);

}  // namespace selfcal
