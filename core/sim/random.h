// Deterministic random numbers for the simulator.
//
// Every number is a pure function of (key, index): a counter-based generator (SplitMix64 as the
// mixing function). Ray noise is addressed by (scan, ray), so the result does not depend on
// which thread draws it or in which order; same seed, same bytes, whatever the thread count.
// We do not use std::normal_distribution: its algorithm differs between standard libraries.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>

namespace selfcal::sim {

inline std::uint64_t SplitMix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// A key for a sub-stream: mixes a parent key with a label and an index.
inline std::uint64_t SubKey(std::uint64_t parent, std::uint64_t label, std::uint64_t index = 0) {
  return SplitMix64(SplitMix64(parent ^ SplitMix64(label)) + index);
}

// Numbers addressed by index within one stream.
class CounterRandom {
 public:
  explicit CounterRandom(std::uint64_t key) : key_(key) {}

  // Uniform in (0, 1), 53 bits.
  double Uniform(std::uint64_t index) const {
    const std::uint64_t bits = SplitMix64(key_ ^ SplitMix64(index)) >> 11;
    return (static_cast<double>(bits) + 0.5) * 0x1.0p-53;
  }
  // Standard normal by Box-Muller from uniforms 2*index and 2*index+1.
  double Gaussian(std::uint64_t index) const {
    const double u1 = Uniform(2 * index);
    const double u2 = Uniform(2 * index + 1);
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
  }

 private:
  std::uint64_t key_;
};

// A sequential stream for planning and ground truth (single-threaded code).
class Random {
 public:
  explicit Random(std::uint64_t key) : counter_(key) {}
  double Uniform() { return counter_.Uniform(next_++); }
  double Uniform(double low, double high) { return low + (high - low) * Uniform(); }
  double Gaussian() { return counter_.Gaussian(next_++); }
  // Integer in [0, count).
  int Index(int count) {
    const int i = static_cast<int>(Uniform() * count);
    return i < count ? i : count - 1;
  }

 private:
  CounterRandom counter_;
  std::uint64_t next_ = 0;
};

}  // namespace selfcal::sim
