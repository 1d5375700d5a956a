// SCIP 2.0 commands, host to sensor (protocols.md 1.2, 1.4). Pure string building: every
// function returns the bytes to write, LF-terminated, or an error naming the bad field.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "core/util/expected.h"

namespace selfcal::scip {

// Longest "string characters" tag a command may carry after ';' (echoed back by the sensor).
inline constexpr std::size_t kMaxTagLength = 16;

// The fixed commands without parameters.
enum class SimpleCommand { kVV, kPP, kII, kBM, kQT, kRS, kTM0, kTM1, kTM2 };
std::string_view SimpleCommandName(SimpleCommand command);

// "VV\n", or "VV;tag\n" with a tag. Error when the tag is too long or not printable.
Expected<std::string> EncodeSimple(SimpleCommand command, std::string_view tag = {});

// The scan commands: G* one scan, M* a stream, H*/N* multi-echo (single/stream).
// *S: 2-character ranges; *D: 3-character ranges; *E: 3-character range + 3-character intensity.
enum class ScanType { kGD, kGS, kGE, kHD, kHE, kMD, kMS, kME, kND, kNE };

struct ScanTypeInfo {
  std::string_view name;  // "MD"
  bool streaming;         // M*, N*: carries skip and count
  int value_width;        // characters per range (2 or 3)
  bool intensity;         // each echo carries range and intensity
  bool multi_echo;        // further echoes follow '&'
};
const ScanTypeInfo& Info(ScanType type);

struct ScanRequest {
  ScanType type = ScanType::kMD;
  int start_step = 0;  // 0..9999
  int end_step = 0;    // start_step..9999
  int cluster = 1;     // 0..99 steps merged into one value (0 and 1 both mean none)
  int skip = 0;        // streaming only: scans skipped between two sent scans, 0..9
  int count = 0;       // streaming only: scans to send, 0..99; 0 = until QT
};

// Number of values (steps after clustering) a scan of `request` carries.
int ValuesPerScan(const ScanRequest& request);

// "MD0000108001000\n" and the like.
Expected<std::string> EncodeScanRequest(const ScanRequest& request, std::string_view tag = {});

// "SS115200\n": change the RS-232 bit rate (6 digits, 0..999999).
Expected<std::string> EncodeBaudChange(int baud);

}  // namespace selfcal::scip
