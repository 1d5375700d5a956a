// Meaning of SCIP 2.0 reply blocks: status codes, VV/PP/II info, TM1 time, scan echoes and scan
// data (protocols.md 1.3-1.6). Errors say where (stream byte offset, line, field).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/util/expected.h"
#include "protocols/scip/block.h"
#include "protocols/scip/commands.h"

namespace selfcal::scip {

// What a status code means for the command it answers (spec p.11/13, urg_sim), e.g.
// ("MD", "04") -> "end step out of range".
std::string StatusMeaning(std::string_view command, std::string_view status);
// Whether `status` reports success for `command` (BM "02" = laser already on, TM0 "02" /
// TM2 "03" = already in that mode, SS "03"/"04"/"0F" as urg_library accepts, "99" = scan data).
bool IsSuccess(std::string_view command, std::string_view status);

// What a status says about the command it answers, as a type to branch on.
enum class StatusKind {
  kDone,                // 00, or a code that IsSuccess accepts ("already so")
  kScanData,            // 99: a streamed scan
  kTimeAdjustMode,      // 0E: undefined command, or refused in time-adjust mode (TM2 leaves it)
  kDenied,              // 10 to a command other than a scan request: denied in the sensor's
                        // current state (a UTM answers TM0 and BM so while it still boots)
  kRefused,             // any other code the command does not accept (bad parameter, laser off)
  kMeasurementStopped,  // 21..49: the sensor stopped measuring to verify an error
  kHardwareTrouble,     // 50..97, 0L
};
StatusKind ClassifyStatus(std::string_view command, std::string_view status);

// A reply whose status did not carry out its command: callers branch on `kind`, never on text.
struct Refusal {
  std::string command;  // the echo, e.g. "MD0000108001000"
  std::string status;   // the 2 characters, e.g. "04"
  StatusKind kind = StatusKind::kRefused;

  std::string Meaning() const { return StatusMeaning(command, status); }
  // "<command> answered <status> (<meaning>)".
  std::string Describe() const;
};
// The refusal in `block` unless its status is kDone for the command it echoes.
std::optional<Refusal> RefusalOf(const Block& block);

// What an SS reply means for the host's serial port. Only 00 moves the sensor to the new rate, and
// the host must follow; the other codes IsSuccess accepts for SS (03 already at that rate, 04 and
// 0F not supported, as over USB) leave the link at the rate in use; anything else refuses.
enum class BaudChange { kSwitched, kUnchanged, kRefused };
BaudChange ClassifyBaudChange(std::string_view status);

// "KEY:VALUE;" lines of a VV, PP or II reply, in order. Error on a malformed line.
Expected<std::map<std::string, std::string>> DecodeInfo(const Block& block);

struct Version {
  std::string vendor, product, firmware, protocol, serial;
};
Expected<Version> DecodeVersion(const Block& block);
// The data lines of a VV reply as a sensor sends them (for the simulator and tests).
void AppendVersion(std::string& out, const Version& version);

// PP: the sensor's geometry. Steps are mirror positions; step k points at
// (k - front_step) * 2 pi / steps_per_rotation rad.
struct Parameters {
  std::string model;
  int min_range_mm = 0;        // DMIN
  int max_range_mm = 0;        // DMAX
  int steps_per_rotation = 0;  // ARES
  int first_step = 0;          // AMIN
  int last_step = 0;           // AMAX
  int front_step = 0;          // AFRT
  int rotation_rpm = 0;        // SCAN
};
Expected<Parameters> DecodeParameters(const Block& block);
// The data lines of a PP reply as a sensor sends them (for the simulator and tests).
void AppendParameters(std::string& out, const Parameters& parameters);

// TM1: the device time [ms] (4 characters, wraps at 2^24).
Expected<std::uint32_t> DecodeTime(const Block& block);

// The echo of a scan command; for streamed scans `request.count` is the number of scans that
// remain after this one (0 when streaming without end).
struct ScanEcho {
  ScanRequest request;
  std::string tag;
};
// Error when the echo is not a scan command with well-formed parameters.
Expected<ScanEcho> ParseScanEcho(std::string_view echo);

// A decoded scan. ranges_mm and intensities hold the first echo of each value; with multi-echo
// commands every echo of value i is in echo_ranges_mm[echo_begin[i] .. echo_begin[i + 1]).
// Vectors are reused between scans (no allocation in steady state).
struct ScanData {
  std::uint32_t timestamp_ms = 0;
  std::vector<std::uint32_t> ranges_mm;
  std::vector<std::uint32_t> intensities;  // empty unless the command carries intensity
  std::vector<std::uint32_t> echo_ranges_mm;
  std::vector<std::uint32_t> echo_intensities;
  std::vector<std::uint32_t> echo_begin;  // size values + 1 (multi-echo commands only)
};

// Decodes the data lines of a scan reply (status 00 for G*/H*, 99 for streamed scans) as the
// command in `echo` asked. Errors on a wrong value count, a bad character, a missing timestamp,
// each naming the stream byte offset.
Status DecodeScan(const Block& block, const ScanEcho& echo, ScanData& out);

// Encodes scan data as a sensor does (for the simulator and tests): the timestamp line and the
// value stream cut into 64-character lines. `ranges_mm` has one entry per value; with multi-echo
// types `extra_echoes` (optional) lists further echoes per value.
struct ScanValues {
  std::uint32_t timestamp_ms = 0;
  std::vector<std::uint32_t> ranges_mm;
  std::vector<std::uint32_t> intensities;                // used by *E types
  std::vector<std::vector<std::uint32_t>> extra_ranges;  // multi-echo: per value, 0..2 more
  std::vector<std::vector<std::uint32_t>> extra_intensities;
};
void AppendScanData(std::string& out, ScanType type, const ScanValues& values);

}  // namespace selfcal::scip
