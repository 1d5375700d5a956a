#include "drivers/wenglor/picture_counter.h"

#include "drivers/wenglor/ethernet_scanner_api.h"

namespace selfcal::wenglor {

PictureCounter::Step PictureCounter::Update(int raw) {
  constexpr int kModulo = api::kPictureCounterModulo;
  raw = ((raw % kModulo) + kModulo) % kModulo;
  Step step;
  if (!has_last_) {
    has_last_ = true;
    last_raw_ = raw;
    unwrapped_ = raw;
    step.unwrapped = unwrapped_;
    return step;
  }
  const int delta = ((raw - last_raw_) % kModulo + kModulo) % kModulo;
  last_raw_ = raw;
  if (delta == 0) {
    step.repeated = true;
  } else if (delta > kModulo / 2) {
    // A step of more than half the range is read as the counter going backwards (a sensor that
    // restarted), not as 32768 or more lost profiles: at the 500 Hz default that would be over a
    // minute of silence, which the data timeout turns into a reconnection long before.
    step.restarted = true;
    unwrapped_ += 1;
  } else {
    unwrapped_ += delta;
    step.lost = delta - 1;
  }
  step.unwrapped = unwrapped_;
  return step;
}

}  // namespace selfcal::wenglor
