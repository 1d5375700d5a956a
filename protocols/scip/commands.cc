#include "protocols/scip/commands.h"

#include <array>
#include <charconv>
#include <cstdio>

namespace selfcal::scip {
namespace {

Status CheckTag(std::string_view tag) {
  if (tag.size() > kMaxTagLength) {
    return Error{"tag of " + std::to_string(tag.size()) + " characters exceeds the limit of " +
                 std::to_string(kMaxTagLength)};
  }
  for (std::size_t i = 0; i < tag.size(); ++i) {
    const auto c = static_cast<unsigned char>(tag[i]);
    if (c < 0x21 || c > 0x7E) {
      return Error{"tag character " + std::to_string(i) + " is not printable ASCII"};
    }
  }
  return OkStatus();
}

std::string WithTag(std::string command, std::string_view tag) {
  if (!tag.empty()) {
    command.push_back(';');
    command.append(tag);
  }
  command.push_back('\n');
  return command;
}

void AppendDigits(std::string& out, int value, int digits) {
  char buffer[12];
  std::snprintf(buffer, sizeof(buffer), "%0*d", digits, value);
  out.append(buffer);
}

constexpr std::array<ScanTypeInfo, 10> kScanTypes = {{
    {"GD", false, 3, false, false},
    {"GS", false, 2, false, false},
    {"GE", false, 3, true, false},
    {"HD", false, 3, false, true},
    {"HE", false, 3, true, true},
    {"MD", true, 3, false, false},
    {"MS", true, 2, false, false},
    {"ME", true, 3, true, false},
    {"ND", true, 3, false, true},
    {"NE", true, 3, true, true},
}};

}  // namespace

std::string_view SimpleCommandName(SimpleCommand command) {
  switch (command) {
    case SimpleCommand::kVV:
      return "VV";
    case SimpleCommand::kPP:
      return "PP";
    case SimpleCommand::kII:
      return "II";
    case SimpleCommand::kBM:
      return "BM";
    case SimpleCommand::kQT:
      return "QT";
    case SimpleCommand::kRS:
      return "RS";
    case SimpleCommand::kTM0:
      return "TM0";
    case SimpleCommand::kTM1:
      return "TM1";
    case SimpleCommand::kTM2:
      return "TM2";
  }
  return "??";
}

Expected<std::string> EncodeSimple(SimpleCommand command, std::string_view tag) {
  if (auto status = CheckTag(tag); !status) return status.error();
  return WithTag(std::string(SimpleCommandName(command)), tag);
}

std::string EncodeNumbered(SimpleCommand command, std::uint64_t sequence) {
  // At most 20 digits: always a valid tag.
  return WithTag(std::string(SimpleCommandName(command)), std::to_string(sequence));
}

std::optional<std::uint64_t> SequenceOf(std::string_view echo, SimpleCommand command) {
  const std::string_view name = SimpleCommandName(command);
  if (echo.size() <= name.size() + 1 || !echo.starts_with(name) || echo[name.size()] != ';') {
    return std::nullopt;
  }
  const std::string_view digits = echo.substr(name.size() + 1);
  std::uint64_t sequence = 0;
  const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), sequence);
  if (error != std::errc() || end != digits.data() + digits.size()) return std::nullopt;
  return sequence;
}

std::string_view EchoOf(std::string_view command) { return command.substr(0, command.find('\n')); }

const ScanTypeInfo& Info(ScanType type) { return kScanTypes[static_cast<std::size_t>(type)]; }

std::optional<ScanType> ScanTypeNamed(std::string_view letters) {
  for (std::size_t i = 0; i < kScanTypes.size(); ++i) {
    if (kScanTypes[i].name == letters) return static_cast<ScanType>(i);
  }
  return std::nullopt;
}

int ValuesPerScan(const ScanRequest& request) {
  const int cluster = request.cluster <= 1 ? 1 : request.cluster;
  const int steps = request.end_step - request.start_step + 1;
  return steps <= 0 ? 0 : (steps + cluster - 1) / cluster;
}

Expected<std::string> EncodeScanRequest(const ScanRequest& request, std::string_view tag) {
  const ScanTypeInfo& info = Info(request.type);
  const std::string name(info.name);
  if (request.start_step < 0 || request.start_step > 9999) {
    return Error{name + ": start step " + std::to_string(request.start_step) + " outside 0..9999"};
  }
  if (request.end_step < request.start_step || request.end_step > 9999) {
    return Error{name + ": end step " + std::to_string(request.end_step) + " outside " +
                 std::to_string(request.start_step) + "..9999"};
  }
  if (request.cluster < 0 || request.cluster > 99) {
    return Error{name + ": cluster count " + std::to_string(request.cluster) + " outside 0..99"};
  }
  if (info.streaming && (request.skip < 0 || request.skip > 9)) {
    return Error{name + ": skip " + std::to_string(request.skip) + " outside 0..9"};
  }
  if (info.streaming && (request.count < 0 || request.count > 99)) {
    return Error{name + ": scan count " + std::to_string(request.count) + " outside 0..99"};
  }
  if (auto status = CheckTag(tag); !status) return Error{name + ": " + status.error().message};
  std::string out = name;
  AppendDigits(out, request.start_step, 4);
  AppendDigits(out, request.end_step, 4);
  AppendDigits(out, request.cluster, 2);
  if (info.streaming) {
    AppendDigits(out, request.skip, 1);
    AppendDigits(out, request.count, 2);
  }
  return WithTag(std::move(out), tag);
}

bool IsEchoOf(std::string_view echo, const ScanRequest& request) {
  ScanRequest without_count = request;
  without_count.count = 0;
  auto command = EncodeScanRequest(without_count);
  if (!command.ok()) return false;
  std::string_view expected = EchoOf(*command);
  // The count is the last two digits of a streaming command (protocols.md 1.4).
  if (Info(request.type).streaming) expected.remove_suffix(2);
  return echo.starts_with(expected);
}

Expected<std::string> EncodeBaudChange(int baud) {
  if (baud <= 0 || baud > 999999) {
    return Error{"SS: bit rate " + std::to_string(baud) + " outside 1..999999"};
  }
  std::string out = "SS";
  AppendDigits(out, baud, 6);
  out.push_back('\n');
  return out;
}

}  // namespace selfcal::scip
