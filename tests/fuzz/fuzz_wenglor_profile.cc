// The Wenglor driver's profile decoding (WenglorScanner::Connect and Poll) over a stand-in for
// the vendor library that answers from the fuzz input (fuzz_wenglor_library.cc): any return
// code, picture counter, column count and coordinate. Properties: never a crash; a profile holds
// at most the library's columns and every coordinate is a finite number of metres or NaN.
#include <dlfcn.h>

#include <cmath>
#include <cstdint>
#include <memory>

#include "drivers/wenglor/wenglor_scanner.h"

namespace {

using namespace selfcal::wenglor;
using SetInput = void (*)(const std::uint8_t*, std::size_t);

struct Fixture {
  std::unique_ptr<WenglorScanner> one_signal, two_signals;
  SetInput set_input = nullptr;
};

std::unique_ptr<WenglorScanner> Scanner(int signals) {
  WenglorConfig config;
  config.library_path = SELFCAL_FUZZ_WENGLOR_LIBRARY;
  config.connect_timeout_ms = 10;
  config.signal_selection = signals == 2 ? 1 : 0;
  config.signals_per_column = signals;
  auto scanner = WenglorScanner::Create(config);
  if (!scanner.ok()) __builtin_trap();
  return std::move(*scanner);
}

Fixture& Get() {
  static Fixture fixture = [] {
    Fixture f;
    f.one_signal = Scanner(1);
    f.two_signals = Scanner(2);
    void* library = dlopen(SELFCAL_FUZZ_WENGLOR_LIBRARY, RTLD_NOW | RTLD_NOLOAD);
    if (library == nullptr) __builtin_trap();
    f.set_input = reinterpret_cast<SetInput>(dlsym(library, "FuzzWenglorSetInput"));
    if (f.set_input == nullptr) __builtin_trap();
    return f;
  }();
  return fixture;
}

bool MetresOrNan(float v) { return std::isnan(v) || (std::isfinite(v) && std::abs(v) < 1e6f); }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  Fixture& fixture = Get();
  WenglorScanner& scanner = data[0] & 1 ? *fixture.two_signals : *fixture.one_signal;
  fixture.set_input(data + 1, size - 1);
  if (!scanner.Connect().ok()) return 0;
  static Profile profile;
  for (int i = 0; i < 64; ++i) {
    const PollResult result = scanner.Poll(profile);
    if (result == PollResult::kLinkLost) break;
    if (result != PollResult::kProfile) continue;
    if (profile.num_points < 0 || profile.num_points > scanner.capacity()) __builtin_trap();
    for (int k = 0; k < profile.num_points; ++k) {
      const auto j = static_cast<std::size_t>(k);
      if (!MetresOrNan(profile.x[j]) || !MetresOrNan(profile.z[j])) __builtin_trap();
    }
  }
  (void)scanner.FifoFillPercent();
  scanner.Disconnect();
  return 0;
}
