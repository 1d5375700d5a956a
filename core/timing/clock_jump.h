// Why a clock estimator stopped trusting its history. Typed, so that callers decide with a
// switch (restart the mapping, end a session) instead of comparing message text.
#pragma once

#include <string_view>

namespace selfcal::timing {

enum class ClockJump {
  kNone,
  kBackwards,   // the device clock went back or stood still: the device restarted its clock
  kForward,     // the device clock leapt ahead further than any gap the stream can have
  kOffTheLine,  // the host receive time is far from where the fitted line predicts it
};

constexpr std::string_view ToString(ClockJump jump) {
  switch (jump) {
    case ClockJump::kNone:
      return "no jump";
    case ClockJump::kBackwards:
      return "went backwards";
    case ClockJump::kForward:
      return "leapt forward";
    case ClockJump::kOffTheLine:
      return "left the fitted line";
  }
  return "unknown";
}

}  // namespace selfcal::timing
