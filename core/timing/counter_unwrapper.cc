#include "core/timing/counter_unwrapper.h"

namespace selfcal::timing {

CounterOptions CounterOptions::Bits(int bits, Backwards backwards) {
  CounterOptions options;
  options.modulus = std::int64_t{1} << bits;
  options.backwards = backwards;
  return options;
}

CounterStep CounterUnwrapper::Update(std::int64_t raw) {
  const std::int64_t m = options_.modulus;
  const std::int64_t value = ((raw - options_.first_value) % m + m) % m;
  CounterStep step;
  if (!has_last_) {
    has_last_ = true;
    last_ = value;
    unwrapped_ = value + options_.first_value;
    step.unwrapped = unwrapped_;
    return step;
  }
  using Backwards = CounterOptions::Backwards;
  const std::int64_t forward = ((value - last_) % m + m) % m;
  const bool forward_only = options_.backwards == Backwards::kNever;
  if (forward == 0 && !forward_only) {
    step.kind = CounterStepKind::kRepeated;
  } else if (forward > m / 2 && !forward_only) {
    step.kind = CounterStepKind::kBackwards;
    switch (options_.backwards) {
      case Backwards::kFollow:
        step.advance = forward - m;
        break;
      case Backwards::kRestart:
        step.advance = 1;
        break;
      case Backwards::kIgnore:
      case Backwards::kNever:
        step.unwrapped = unwrapped_;
        return step;  // the newest value stays the reference
    }
  } else {
    step.kind = CounterStepKind::kForward;
    step.advance = forward == 0 ? m : forward;
    step.lost = step.advance - 1;
  }
  last_ = value;
  unwrapped_ += step.advance;
  step.unwrapped = unwrapped_;
  return step;
}

}  // namespace selfcal::timing
