// SCIP 2.0 commands, host to sensor (protocols.md 1.2, 1.4). Pure string building: every
// function returns the bytes to write, LF-terminated, or an error naming the bad field.
#pragma once

#include <cstdint>
#include <optional>
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

// "TM1;42\n": a command tagged with a sequence number, so that a reply is matched to its own
// request even when replies come late or get lost.
std::string EncodeNumbered(SimpleCommand command, std::uint64_t sequence);
// The sequence number of an echo of EncodeNumbered(command, n); nullopt for any other echo.
std::optional<std::uint64_t> SequenceOf(std::string_view echo, SimpleCommand command);

// The echo line a sensor answers `command` (bytes from an Encode function) with: the command
// without its LF.
std::string_view EchoOf(std::string_view command);

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
// The scan type of two letters ("MD"); nullopt for letters that name no scan command.
std::optional<ScanType> ScanTypeNamed(std::string_view letters);

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

// Whether `echo` answers `request` (without tag). A stream's echo counts its remaining scans
// down, so the scan count is not compared; anything else that differs is another command's.
bool IsEchoOf(std::string_view echo, const ScanRequest& request);

// "SS115200\n": change the RS-232 bit rate (6 digits, 0..999999).
Expected<std::string> EncodeBaudChange(int baud);

}  // namespace selfcal::scip
