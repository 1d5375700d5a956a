// Any bytes as the Wenglor info XML: an error or a complete, plausible ScannerInfo; never a crash.
#include <cstdint>
#include <string_view>

#include "protocols/wenglor/scanner_info.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view xml(reinterpret_cast<const char*>(data), size);
  auto info = selfcal::wenglor::ParseScannerInfo(xml);
  if (info.ok() && (info->order_number.empty() || info->measuring_range_z <= 0 ||
                    info->pixel_x_max < 1 || info->working_range_z_start < 0)) {
    __builtin_trap();
  }
  return 0;
}
