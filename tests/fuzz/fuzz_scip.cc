// Any bytes as a SCIP 2.0 reply stream: every block is an error or a reply whose decoded values
// are complete; never a crash, a hang or unbounded memory.
#include <cstdint>
#include <string_view>

#include "protocols/scip/block.h"
#include "protocols/scip/replies.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  // The first byte picks the chunk size, so block boundaries fall anywhere in a read.
  const std::size_t chunk = 1 + data[0] % 64;
  const std::string_view bytes(reinterpret_cast<const char*>(data + 1), size - 1);
  selfcal::scip::BlockFramer framer(/*max_block_bytes=*/4096);
  selfcal::scip::ScanData scan;
  for (std::size_t i = 0; i <= bytes.size(); i += chunk) {
    framer.Append(bytes.substr(i, chunk));
    while (auto block = framer.Next()) {
      if (!block->ok()) continue;
      const auto& b = **block;
      if (auto echo = selfcal::scip::ParseScanEcho(b.echo); echo.ok()) {
        if (selfcal::scip::DecodeScan(b, *echo, scan).ok() &&
            scan.ranges_mm.size() !=
                static_cast<std::size_t>(selfcal::scip::ValuesPerScan(echo->request))) {
          __builtin_trap();
        }
      }
      (void)selfcal::scip::DecodeParameters(b);
      (void)selfcal::scip::DecodeVersion(b);
      (void)selfcal::scip::DecodeTime(b);
      (void)selfcal::scip::StatusMeaning(b.echo, b.status);
    }
    if (framer.buffered() > 4096 + chunk) __builtin_trap();
  }
  return 0;
}
