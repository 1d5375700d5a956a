// Unwraps the sensor's 16-bit picture counter and reports lost profiles: the counter advances by
// one per exposure, so a step of n > 1 means n - 1 profiles never reached us.
#pragma once

#include <cstdint>

namespace selfcal::wenglor {

class PictureCounter {
 public:
  struct Step {
    std::int64_t unwrapped = 0;  // counter since the first profile of this connection
    std::int64_t lost = 0;       // profiles missing between the previous one and this one
    bool repeated = false;       // the same counter again (a duplicate profile)
    bool restarted = false;      // the counter went backwards: the sensor restarted counting
  };

  // `raw` is the counter the library reported (0 .. 65535).
  Step Update(int raw);
  // Forgets the history (after a reconnection the sensor may count from anywhere).
  void Reset() { has_last_ = false; }

 private:
  bool has_last_ = false;
  int last_raw_ = 0;
  std::int64_t unwrapped_ = 0;
};

}  // namespace selfcal::wenglor
