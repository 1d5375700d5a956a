// Unwraps a device counter that wraps around (the Hokuyo's 24-bit millisecond clock, the
// Wenglor's 16-bit picture counter, GigE Vision 1 block ids) into a 64-bit count, and says what
// each step was: the first value, a step forward (with the values skipped: lost messages), the
// same value again, or a step backwards.
//
// A step is read as the shortest way round: forward by up to half the range, else backwards.
// What a backward step means is the caller's: timestamps read out of order step back a little
// (kFollow: the unwrapped value goes back too); a counter of messages steps back only when the
// device restarted counting (kRestart: the unwrapped value continues by one, so it never repeats).
// Messages that can arrive out of order (UDP) step back when a late one comes: it is reported and
// the newest value stays the reference (kIgnore). A counter that cannot step back or repeat (a
// CANopen SYNC counter) reads every step forward, the same value again as one whole turn (kNever).
#pragma once

#include <cstdint>

namespace selfcal::timing {

struct CounterOptions {
  enum class Backwards { kFollow, kRestart, kIgnore, kNever };
  std::int64_t modulus = std::int64_t{1} << 16;  // number of distinct values
  std::int64_t first_value = 0;                  // the lowest value (1: the counter skips 0)
  Backwards backwards = Backwards::kRestart;

  // A counter of `bits` bits: 0 .. 2^bits - 1.
  static CounterOptions Bits(int bits, Backwards backwards);
};

enum class CounterStepKind { kFirst, kForward, kRepeated, kBackwards };

struct CounterStep {
  CounterStepKind kind = CounterStepKind::kFirst;
  std::int64_t unwrapped = 0;  // the first raw value, then moved by each step (the newest value)
  std::int64_t advance = 0;    // change of `unwrapped` (0 for the first value)
  std::int64_t lost = 0;       // values skipped by a forward step
  bool repeated() const { return kind == CounterStepKind::kRepeated; }
  bool went_backwards() const { return kind == CounterStepKind::kBackwards; }
};

class CounterUnwrapper {
 public:
  explicit CounterUnwrapper(CounterOptions options) : options_(options) {}

  // `raw` is the counter as the device reported it; out-of-range values are taken modulo.
  CounterStep Update(std::int64_t raw);
  // Forgets the history (after a reconnection the device may count from anywhere).
  void Reset() { has_last_ = false; }

 private:
  CounterOptions options_;
  bool has_last_ = false;
  std::int64_t last_ = 0;  // normalised: raw - first_value, in [0, modulus)
  std::int64_t unwrapped_ = 0;
};

}  // namespace selfcal::timing
