// SCIP 2.0 commands as a sensor reads them (host to sensor, protocols.md 1.2 and 1.4): the inverse
// of commands.h, for the simulator and for the echo a host reads back. A line a sensor cannot
// carry out yields the refusal it answers, with the status a sensor sends, checked in urg_sim's
// order: the framing first (ParseCommandLine), then the parameters of the command.
#pragma once

#include <string_view>
#include <variant>

#include "protocols/scip/commands.h"
#include "protocols/scip/replies.h"

namespace selfcal::scip {

// Every command a sensor knows, by its two letters (TM carries its control code as a parameter;
// every scan command is kScan with its ScanType).
enum class CommandName { kVV, kPP, kII, kBM, kQT, kRS, kRT, kRB, kTM, kSS, kScan };

// A command line cut at the fixed length of its command.
struct CommandLine {
  std::string_view text;  // the whole line without its LF: what the sensor echoes
  CommandName name = CommandName::kVV;
  ScanType scan_type = ScanType::kMD;  // kScan only
  std::string_view parameters;         // the characters after the two letters, before ';'
  std::string_view tag;                // after ';', empty without one
};

// The parsed value, or the refusal a sensor answers the line with.
template <typename T>
using OrRefusal = std::variant<T, Refusal>;

// 0E: an undefined command; 0C: shorter than its command's fixed length; 0D: longer without ';'
// after it, or a tag over kMaxTagLength (urg_sim's validateExtraString). The result's views point
// into `line`.
OrRefusal<CommandLine> ParseCommandLine(std::string_view line);

// Whether a sensor in time-adjust mode (after TM0) carries out `name`; it answers anything else
// with 0E until TM2.
bool AllowedInTimeAdjustMode(CommandName name);

// TM's control code as kTM0, kTM1 or kTM2; 01 for any other code.
OrRefusal<SimpleCommand> ParseTimeCommand(const CommandLine& command);

// SS's bit rate; 01 when its six characters are not digits. Which rates a sensor supports is the
// sensor's own (it answers 02 for the others).
OrRefusal<int> ParseBaudChange(const CommandLine& command);

// The steps a sensor measures (PP's AMIN..AMAX); the default admits every step a command can name.
struct StepRange {
  int first = 0;
  int last = 9999;
};

// A scan command's request and tag: 01, 02, 03 when the start step, end step or cluster count is
// not numeric; 04 when the steps leave `steps`; 05 when the end step is before the start step;
// then, for streaming commands, 06 and 07 when the skip or scan count is not numeric. Whether the
// laser is on (10) is the sensor's state, not the line's.
OrRefusal<ScanEcho> ParseScanCommand(const CommandLine& command, StepRange steps = {});

}  // namespace selfcal::scip
