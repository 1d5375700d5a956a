// The sensor's info XML (EthernetScanner_GetInfo(..., "xml"), DLL interface description §8.1):
// order number (the model), working range and field width. Parsed without an XML library: the
// driver needs a handful of leaf elements, looked up by tag name wherever they are nested.
#pragma once

#include <string>
#include <string_view>

#include "core/util/expected.h"

namespace selfcal::wenglor {

struct ScannerInfo {
  std::string order_number;          // <ordernumber>, e.g. "MLSL236"
  std::string serial_number;         // <serialnumber>, empty when absent
  double working_range_z_start = 0;  // m, <workingrange_z_start> (mm on the wire)
  double measuring_range_z = 0;      // m, <measuringrange_z> (mm)
  double field_width_x_start = 0;    // m, <fieldwidth_x_start> (mm): width at the near end
  double field_width_x_end = 0;      // m, <fieldwidth_x_end> (mm): width at the far end
  int pixel_x_max = 0;               // <pixel_x_max>: columns per profile

  double working_range_z_end() const { return working_range_z_start + measuring_range_z; }
};

// Longer than any scanner's info (a few kB): a larger text is not an info reply.
inline constexpr std::size_t kMaxScannerInfoBytes = 1 << 20;

// Parses the info text. Errors name the element and its byte offset in `xml`; a text over
// kMaxScannerInfoBytes is an error before any search.
Expected<ScannerInfo> ParseScannerInfo(std::string_view xml);

}  // namespace selfcal::wenglor
