// Which of the sensor's intrinsics the engine calibrates (docs/engine.md, deviation 17), as the
// sensor file's calibrate_intrinsics and the CLI's --intrinsics write it: "none", "auto" (the
// engine picks what the sensor and the mask can show) or a '+'-list of scale, offset and focal.
// Header-only, so that protocols/model_file checks a sensor file without linking the engine.
#pragma once

#include <algorithm>
#include <string>

namespace selfcal::calib {

struct IntrinsicsChoice {
  bool scale = false;
  bool offset = false;
  bool focal = false;
  bool automatic = false;
  bool Any() const { return scale || offset || focal || automatic; }
};

// Reads `text` into *choice. Returns what is wrong with it, or an empty string (then *choice
// holds it; on an error *choice is unchanged).
inline std::string ParseIntrinsicsChoice(const std::string& text, IntrinsicsChoice* choice) {
  IntrinsicsChoice parsed;
  parsed.automatic = text == "auto";
  if (text != "none" && text != "auto") {
    std::size_t begin = 0;
    while (begin <= text.size()) {
      const std::size_t end = std::min(text.find('+', begin), text.size());
      const std::string item = text.substr(begin, end - begin);
      bool* chosen = item == "scale"    ? &parsed.scale
                     : item == "offset" ? &parsed.offset
                     : item == "focal"  ? &parsed.focal
                                        : nullptr;
      if (chosen == nullptr)
        return "must be none, auto or a '+'-list of scale, offset and focal, not '" + text + "'";
      *chosen = true;
      begin = end + 1;
    }
  }
  *choice = parsed;
  return {};
}

}  // namespace selfcal::calib
