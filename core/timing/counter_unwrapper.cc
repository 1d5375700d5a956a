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
  const std::int64_t forward = ((value - last_) % m + m) % m;
  last_ = value;
  const bool forward_only = options_.backwards == CounterOptions::Backwards::kNever;
  if (forward == 0 && !forward_only) {
    step.kind = CounterStepKind::kRepeated;
  } else if (forward > m / 2 && !forward_only) {
    step.kind = CounterStepKind::kBackwards;
    step.advance = options_.backwards == CounterOptions::Backwards::kFollow ? forward - m : 1;
  } else {
    step.kind = CounterStepKind::kForward;
    step.advance = forward == 0 ? m : forward;
    step.lost = step.advance - 1;
  }
  unwrapped_ += step.advance;
  step.unwrapped = unwrapped_;
  return step;
}

}  // namespace selfcal::timing
