#include "protocols/scip/replies.h"

#include <array>

#include "protocols/scip/command_parser.h"
#include "protocols/scip/encoding.h"

namespace selfcal::scip {
namespace {

// The numeric value of a two-digit status ("21" -> 21); nullopt for "0E", "0L" and the like.
std::optional<int> NumericStatus(std::string_view status) {
  if (status.size() != 2) return std::nullopt;
  return DecodeDecimal(status);
}

// The keys of a VV reply and of a PP reply, in the order a sensor sends them.
constexpr std::array<std::pair<const char*, std::string Version::*>, 5> kVersionKeys = {{
    {"VEND", &Version::vendor},
    {"PROD", &Version::product},
    {"FIRM", &Version::firmware},
    {"PROT", &Version::protocol},
    {"SERI", &Version::serial},
}};
constexpr std::array<std::pair<const char*, int Parameters::*>, 7> kParameterKeys = {{
    {"DMIN", &Parameters::min_range_mm},
    {"DMAX", &Parameters::max_range_mm},
    {"ARES", &Parameters::steps_per_rotation},
    {"AMIN", &Parameters::first_step},
    {"AMAX", &Parameters::last_step},
    {"AFRT", &Parameters::front_step},
    {"SCAN", &Parameters::rotation_rpm},
}};

std::string At(std::uint64_t offset) { return "byte " + std::to_string(offset); }

// The value of a key that a VV or PP reply must carry.
Expected<std::string> RequiredValue(const std::map<std::string, std::string>& info,
                                    const Block& block, const char* reply, const char* key) {
  const auto it = info.find(key);
  if (it == info.end()) return Error{At(block.offset) + ": " + reply + " reply lacks " + key};
  return it->second;
}

std::string_view CommandOf(std::string_view echo) {
  if (echo.starts_with("TM") || echo.starts_with("SS")) return echo.substr(0, 2);
  return echo.substr(0, std::min<std::size_t>(2, echo.size()));
}

}  // namespace

std::string StatusMeaning(std::string_view command, std::string_view status) {
  const std::string_view cmd = CommandOf(command);
  if (status == "00") return "ok";
  if (status == "99") return "scan data";
  if (status == "0C") return "command too short";
  if (status == "0D") return "command too long or bad tag separator";
  if (status == "0E") return "undefined command, or refused in time-adjust mode (send TM2)";
  if (status == "0F") return "command not supported by this sensor";
  if (status == "0L") return "sensor in an abnormal state";
  if (cmd == "BM") {
    if (status == "01") return "laser cannot be switched on (malfunction)";
    if (status == "02") return "laser already on";
  }
  if (cmd == "TM") {
    if (status == "01") return "invalid control code";
    if (status == "02") return "already in time-adjust mode";
    if (status == "03") return "time-adjust mode already off";
    if (status == "04") return "not in time-adjust mode";
  }
  if (cmd == "SS") {
    if (status == "01") return "bit rate not numeric";
    if (status == "02") return "bit rate out of range";
    if (status == "03") return "already at that bit rate";
    if (status == "04") return "bit rate not supported by this sensor";
  }
  if (cmd == "RB") {
    if (status == "01") return "reboot armed: send RB again within 1 s";
  }
  if (cmd.size() == 2 && (cmd[0] == 'G' || cmd[0] == 'M' || cmd[0] == 'H' || cmd[0] == 'N')) {
    if (status == "01") return "start step not numeric";
    if (status == "02") return "end step not numeric";
    if (status == "03") return "cluster count not numeric";
    if (status == "04") return "end step out of range";
    if (status == "05") return "end step before start step";
    if (status == "06") return "scan interval not numeric";
    if (status == "07") return "scan count not numeric";
    if (status == "10") return "laser off";
  }
  if (status == "10") return "command denied in the current state (still booting?)";
  if (const auto code = NumericStatus(status)) {
    if (*code >= 21 && *code <= 49) return "measurement stopped to verify an error";
    if (*code >= 50 && *code <= 97) return "hardware trouble";
    if (*code == 98) return "resumed after confirming normal operation";
  }
  return "unknown status";
}

bool IsSuccess(std::string_view command, std::string_view status) {
  const std::string_view cmd = CommandOf(command);
  if (status == "00") return true;
  if (status == "99") {
    return cmd.size() == 2 && (cmd[0] == 'M' || cmd[0] == 'N');
  }
  if (cmd == "BM") return status == "02";
  if (command.starts_with("TM0")) return status == "02";
  if (command.starts_with("TM2")) return status == "03";
  if (cmd == "SS") return status == "03" || status == "04" || status == "0F";
  return false;
}

StatusKind ClassifyStatus(std::string_view command, std::string_view status) {
  const std::string_view cmd = CommandOf(command);
  const bool streaming = cmd.size() == 2 && (cmd[0] == 'M' || cmd[0] == 'N');
  if (status == "99" && streaming) return StatusKind::kScanData;
  if (IsSuccess(command, status)) return StatusKind::kDone;
  if (status == "0E") return StatusKind::kTimeAdjustMode;
  if (status == "0L") return StatusKind::kHardwareTrouble;
  const bool scan_request =
      cmd.size() == 2 && (cmd[0] == 'G' || cmd[0] == 'M' || cmd[0] == 'H' || cmd[0] == 'N');
  if (status == "10" && !scan_request) return StatusKind::kDenied;
  if (const auto code = NumericStatus(status)) {
    if (*code >= 21 && *code <= 49) return StatusKind::kMeasurementStopped;
    if (*code >= 50 && *code <= 97) return StatusKind::kHardwareTrouble;
  }
  return StatusKind::kRefused;
}

BaudChange ClassifyBaudChange(std::string_view status) {
  if (ClassifyStatus("SS", status) != StatusKind::kDone) return BaudChange::kRefused;
  return status == "00" ? BaudChange::kSwitched : BaudChange::kUnchanged;
}

std::string Refusal::Describe() const {
  return command + " answered " + status + " (" + Meaning() + ")";
}

std::optional<Refusal> RefusalOf(const Block& block) {
  const StatusKind kind = ClassifyStatus(block.echo, block.status);
  if (kind == StatusKind::kDone) return std::nullopt;
  return Refusal{block.echo, block.status, kind};
}

Expected<std::map<std::string, std::string>> DecodeInfo(const Block& block) {
  if (block.status != "00") {
    return Error{At(block.offset) + ": " + block.echo + " answered status " + block.status + " (" +
                 StatusMeaning(block.echo, block.status) + ")"};
  }
  std::map<std::string, std::string> info;
  for (std::size_t i = 0; i < block.lines.size(); ++i) {
    const std::string& line = block.lines[i];
    const std::size_t colon = line.find(':');
    if (colon == std::string::npos || colon == 0 || line.back() != ';') {
      return Error{At(block.line_offsets[i]) + ": " + block.echo + " line is not KEY:VALUE; (" +
                   line + ")"};
    }
    info[line.substr(0, colon)] = line.substr(colon + 1, line.size() - colon - 2);
  }
  return info;
}

Expected<Version> DecodeVersion(const Block& block) {
  auto info = DecodeInfo(block);
  if (!info) return info.error();
  Version version;
  for (const auto& [key, field] : kVersionKeys) {
    auto value = RequiredValue(*info, block, "VV", key);
    if (!value) return value.error();
    version.*field = *value;
  }
  return version;
}

Expected<Parameters> DecodeParameters(const Block& block) {
  auto info = DecodeInfo(block);
  if (!info) return info.error();
  Parameters parameters;
  const auto model = info->find("MODL");
  if (model != info->end()) parameters.model = model->second;
  for (const auto& [key, field] : kParameterKeys) {
    auto text = RequiredValue(*info, block, "PP", key);
    if (!text) return text.error();
    // Values are decimal; some firmware appends a unit or comment after a space.
    const auto value = DecodeDecimal(std::string_view(*text).substr(0, text->find(' ')));
    if (!value) {
      return Error{At(block.offset) + ": PP " + key + " is not a number: '" + *text + "'"};
    }
    parameters.*field = *value;
  }
  if (parameters.steps_per_rotation <= 0 || parameters.rotation_rpm <= 0 ||
      parameters.last_step < parameters.first_step ||
      parameters.last_step >= parameters.steps_per_rotation ||
      parameters.front_step < parameters.first_step ||
      parameters.front_step > parameters.last_step) {
    return Error{At(block.offset) + ": PP geometry is inconsistent (ARES " +
                 std::to_string(parameters.steps_per_rotation) + ", AMIN " +
                 std::to_string(parameters.first_step) + ", AMAX " +
                 std::to_string(parameters.last_step) + ", AFRT " +
                 std::to_string(parameters.front_step) + ", SCAN " +
                 std::to_string(parameters.rotation_rpm) + ")"};
  }
  return parameters;
}

Expected<std::uint32_t> DecodeTime(const Block& block) {
  if (!block.echo.starts_with("TM1")) {
    return Error{At(block.offset) + ": expected a TM1 reply, got '" + block.echo + "'"};
  }
  if (block.status != "00") {
    return Error{At(block.offset) + ": TM1 answered status " + block.status + " (" +
                 StatusMeaning(block.echo, block.status) + ")"};
  }
  if (block.lines.size() != 1 || block.lines[0].size() != 4) {
    return Error{At(block.offset) + ": TM1 reply must carry one 4-character time line"};
  }
  const auto value = DecodeValue(block.lines[0]);
  if (!value) return Error{At(block.line_offsets[0]) + ": TM1 time has a bad character"};
  return *value;
}

Expected<ScanEcho> ParseScanEcho(std::string_view echo) {
  // An echo is the command as the host sent it: what a sensor accepts, it reads back.
  const auto line = ParseCommandLine(echo);
  const auto* command = std::get_if<CommandLine>(&line);
  if (command == nullptr && std::get<Refusal>(line).status != "0E") {
    return Error{"echo '" + std::string(echo) + "': " + std::get<Refusal>(line).Meaning()};
  }
  if (command == nullptr || command->name != CommandName::kScan) {
    return Error{"echo '" + std::string(echo) + "' is not a scan command"};
  }
  auto parsed = ParseScanCommand(*command);
  if (const auto* refusal = std::get_if<Refusal>(&parsed)) {
    return Error{"echo '" + std::string(echo) + "': " + refusal->Meaning()};
  }
  return std::get<ScanEcho>(std::move(parsed));
}

void AppendVersion(std::string& out, const Version& version) {
  for (const auto& [key, field] : kVersionKeys) AppendInfoLine(out, key, version.*field);
}

void AppendParameters(std::string& out, const Parameters& parameters) {
  AppendInfoLine(out, "MODL", parameters.model);
  for (const auto& [key, field] : kParameterKeys) {
    AppendInfoLine(out, key, std::to_string(parameters.*field));
  }
}

namespace {

// Walks the value stream of a scan across its data lines (line 0 is the timestamp): a value may
// straddle two lines (protocols.md 1.2).
class ValueStream {
 public:
  ValueStream(const Block& block, std::size_t values) : block_(block), values_(values) {}

  // Stream byte offset of the next character; past the end, the block's (callers report "ends
  // early").
  std::uint64_t Offset() const {
    if (line_ < block_.lines.size()) return block_.line_offsets[line_] + column_;
    return block_.offset;
  }
  bool Next(char& c) {
    SkipEmptyLines(line_, column_);
    if (line_ >= block_.lines.size()) return false;
    c = block_.lines[line_][column_++];
    return true;
  }
  // The next character without consuming it; -1 at the end.
  int Peek() const {
    std::size_t line = line_;
    std::size_t column = column_;
    SkipEmptyLines(line, column);
    if (line >= block_.lines.size()) return -1;
    return static_cast<unsigned char>(block_.lines[line][column]);
  }
  // One value of `chars` characters; `what` and `index` say which in an error.
  Status Read(std::size_t chars, std::uint32_t& value, std::size_t index, const char* what) {
    char buffer[4];
    const std::uint64_t where = Offset();
    for (std::size_t i = 0; i < chars; ++i) {
      if (!Next(buffer[i])) {
        return Error{At(block_.offset) + ": " + block_.echo + " scan data ends in value " +
                     std::to_string(index) + " of " + std::to_string(values_)};
      }
    }
    const auto decoded = DecodeValue(std::string_view(buffer, chars));
    if (!decoded) {
      return Error{At(where) + ": bad character in " + what + " of value " + std::to_string(index)};
    }
    value = *decoded;
    return OkStatus();
  }

 private:
  void SkipEmptyLines(std::size_t& line, std::size_t& column) const {
    while (line < block_.lines.size() && column >= block_.lines[line].size()) {
      ++line;
      column = 0;
    }
  }

  const Block& block_;
  std::size_t values_;
  std::size_t line_ = 1;
  std::size_t column_ = 0;
};

// The status a scan of `echo` must carry and its 4-character timestamp line.
Status DecodeScanTimestamp(const Block& block, const ScanEcho& echo, ScanData& out) {
  const std::string expected_status = Info(echo.request.type).streaming ? "99" : "00";
  if (block.status != expected_status) {
    return Error{At(block.offset) + ": " + block.echo + " status " + block.status + " (" +
                 StatusMeaning(block.echo, block.status) + "), expected " + expected_status +
                 " with scan data"};
  }
  if (block.lines.empty()) {
    return Error{At(block.offset) + ": " + block.echo + " scan has no timestamp line"};
  }
  if (block.lines[0].size() != 4) {
    return Error{At(block.line_offsets[0]) + ": scan timestamp line has " +
                 std::to_string(block.lines[0].size()) + " characters, expected 4"};
  }
  const auto timestamp = DecodeValue(block.lines[0]);
  if (!timestamp) return Error{At(block.line_offsets[0]) + ": scan timestamp has a bad character"};
  out.timestamp_ms = *timestamp;
  return OkStatus();
}

// Empties `out`, keeping its capacity, for `values` values.
void ResetScan(const ScanTypeInfo& info, std::size_t values, ScanData& out) {
  out.ranges_mm.clear();
  out.intensities.clear();
  out.echo_ranges_mm.clear();
  out.echo_intensities.clear();
  out.echo_begin.clear();
  out.ranges_mm.reserve(values);
  if (info.intensity) out.intensities.reserve(values);
}

// Value `index` with all its echoes ('&'-separated for multi-echo commands, at most 3).
Status DecodeScanValue(const ScanTypeInfo& info, std::size_t index, ValueStream& stream,
                       ScanData& out) {
  const std::size_t width = static_cast<std::size_t>(info.value_width);
  if (info.multi_echo) {
    out.echo_begin.push_back(static_cast<std::uint32_t>(out.echo_ranges_mm.size()));
  }
  int echo_count = 0;
  do {
    if (echo_count > 0) {
      char ampersand;
      (void)stream.Next(ampersand);
    }
    if (echo_count >= 3) {
      return Error{At(stream.Offset()) + ": more than 3 echoes in value " + std::to_string(index)};
    }
    std::uint32_t range = 0;
    std::uint32_t intensity = 0;
    if (auto s = stream.Read(width, range, index, "range"); !s) return s;
    if (info.intensity) {
      if (auto s = stream.Read(width, intensity, index, "intensity"); !s) return s;
    }
    if (echo_count == 0) {
      out.ranges_mm.push_back(range);
      if (info.intensity) out.intensities.push_back(intensity);
    }
    if (info.multi_echo) {
      out.echo_ranges_mm.push_back(range);
      if (info.intensity) out.echo_intensities.push_back(intensity);
    }
    ++echo_count;
  } while (info.multi_echo && stream.Peek() == '&');
  return OkStatus();
}

}  // namespace

Status DecodeScan(const Block& block, const ScanEcho& echo, ScanData& out) {
  if (auto status = DecodeScanTimestamp(block, echo, out); !status) return status;
  const ScanTypeInfo& info = Info(echo.request.type);
  const std::size_t values = static_cast<std::size_t>(ValuesPerScan(echo.request));
  ResetScan(info, values, out);
  ValueStream stream(block, values);
  for (std::size_t i = 0; i < values; ++i) {
    if (auto status = DecodeScanValue(info, i, stream, out); !status) return status;
  }
  if (info.multi_echo) {
    out.echo_begin.push_back(static_cast<std::uint32_t>(out.echo_ranges_mm.size()));
  }
  if (stream.Peek() >= 0) {
    return Error{At(stream.Offset()) + ": " + block.echo + " scan carries more than the " +
                 std::to_string(values) + " values requested"};
  }
  return OkStatus();
}

void AppendScanData(std::string& out, ScanType type, const ScanValues& values) {
  const ScanTypeInfo& info = Info(type);
  AppendDataLine(out, EncodeValue(values.timestamp_ms, 4));
  std::string stream;
  stream.reserve(values.ranges_mm.size() * 7);
  for (std::size_t i = 0; i < values.ranges_mm.size(); ++i) {
    AppendEncoded(stream, values.ranges_mm[i], info.value_width);
    if (info.intensity) {
      AppendEncoded(stream, i < values.intensities.size() ? values.intensities[i] : 0,
                    info.value_width);
    }
    if (info.multi_echo && i < values.extra_ranges.size()) {
      for (std::size_t e = 0; e < values.extra_ranges[i].size() && e < 2; ++e) {
        stream.push_back('&');
        AppendEncoded(stream, values.extra_ranges[i][e], info.value_width);
        if (info.intensity) {
          const bool has =
              i < values.extra_intensities.size() && e < values.extra_intensities[i].size();
          AppendEncoded(stream, has ? values.extra_intensities[i][e] : 0, info.value_width);
        }
      }
    }
  }
  AppendDataBlock(out, stream);
}

}  // namespace selfcal::scip
