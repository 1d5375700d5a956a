// Text made safe inside XML or HTML, as element content or a quoted attribute value: & < > " '
// become entities (the URDF export and the session report both write text from model files).
#pragma once

#include <string>
#include <string_view>

namespace selfcal {

std::string MarkupText(std::string_view text);

}  // namespace selfcal
