// How long a test waits for programs and threads that do real work. tools/cross-arm64 runs the
// tests under qemu-user, where code runs tens of times slower than natively, and sets
// SELFCAL_TEST_TIME_SCALE (its emulator's slowdown) so that deadlines and streaming windows
// stretch by that factor. What a test asserts stays the same; only how long it waits changes.
// Natively (the variable unset) the factor is 1.
#pragma once

#include <chrono>
#include <cstdlib>

namespace selfcal::testing {

inline double TimeScale() {
  static const double scale = [] {
    const char* text = std::getenv("SELFCAL_TEST_TIME_SCALE");
    const double value = text != nullptr ? std::strtod(text, nullptr) : 1.0;
    return value > 1.0 ? value : 1.0;
  }();
  return scale;
}

// True under an emulator (a time scale above 1): real-time rates are not the device's there.
inline bool Emulated() { return TimeScale() > 1.0; }

template <class Rep, class Period>
std::chrono::milliseconds Scaled(std::chrono::duration<Rep, Period> wait) {
  return std::chrono::milliseconds(static_cast<long long>(
      std::chrono::duration<double, std::milli>(wait).count() * TimeScale()));
}

inline double ScaledSeconds(double seconds) { return seconds * TimeScale(); }

}  // namespace selfcal::testing
