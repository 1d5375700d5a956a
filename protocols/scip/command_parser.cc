#include "protocols/scip/command_parser.h"

#include <array>
#include <optional>
#include <string>

#include "protocols/scip/encoding.h"

namespace selfcal::scip {
namespace {

Refusal Refuse(std::string_view line, std::string status) {
  const StatusKind kind = ClassifyStatus(line, status);
  return Refusal{std::string(line), std::move(status), kind};
}

struct Fixed {
  std::string_view letters;
  CommandName name;
  std::size_t length;  // of the command without its tag
};
constexpr std::array<Fixed, 10> kFixedCommands = {{
    {"VV", CommandName::kVV, 2},
    {"PP", CommandName::kPP, 2},
    {"II", CommandName::kII, 2},
    {"BM", CommandName::kBM, 2},
    {"QT", CommandName::kQT, 2},
    {"RS", CommandName::kRS, 2},
    {"RT", CommandName::kRT, 2},
    {"RB", CommandName::kRB, 2},
    {"TM", CommandName::kTM, 3},
    {"SS", CommandName::kSS, 8},
}};

// The command the two letters name and its fixed length; nullopt for an undefined one.
std::optional<std::pair<CommandLine, std::size_t>> Identify(std::string_view letters) {
  CommandLine command;
  for (const Fixed& fixed : kFixedCommands) {
    if (fixed.letters == letters) {
      command.name = fixed.name;
      return std::pair{command, fixed.length};
    }
  }
  if (const auto type = ScanTypeNamed(letters)) {
    command.name = CommandName::kScan;
    command.scan_type = *type;
    return std::pair{command, std::size_t{Info(*type).streaming ? 15u : 12u}};
  }
  return std::nullopt;
}

}  // namespace

OrRefusal<CommandLine> ParseCommandLine(std::string_view line) {
  auto identified = Identify(line.substr(0, 2));
  if (!identified) return Refuse(line, "0E");
  auto& [command, length] = *identified;
  if (line.size() < length) return Refuse(line, "0C");
  if (line.size() > length && (line[length] != ';' || line.size() - length - 1 > kMaxTagLength)) {
    return Refuse(line, "0D");
  }
  command.text = line;
  command.parameters = line.substr(2, length - 2);
  if (line.size() > length) command.tag = line.substr(length + 1);
  return command;
}

bool AllowedInTimeAdjustMode(CommandName name) {
  return name == CommandName::kTM || name == CommandName::kRS || name == CommandName::kRT;
}

OrRefusal<SimpleCommand> ParseTimeCommand(const CommandLine& command) {
  switch (command.parameters.empty() ? '\0' : command.parameters[0]) {
    case '0':
      return SimpleCommand::kTM0;
    case '1':
      return SimpleCommand::kTM1;
    case '2':
      return SimpleCommand::kTM2;
    default:
      return Refuse(command.text, "01");
  }
}

OrRefusal<int> ParseBaudChange(const CommandLine& command) {
  const auto baud = DecodeDecimal(command.parameters);
  if (!baud) return Refuse(command.text, "01");
  return *baud;
}

OrRefusal<ScanEcho> ParseScanCommand(const CommandLine& command, StepRange steps) {
  const std::string_view p = command.parameters;
  const auto start = DecodeDecimal(p.substr(0, 4));
  if (!start) return Refuse(command.text, "01");
  const auto end = DecodeDecimal(p.substr(4, 4));
  if (!end) return Refuse(command.text, "02");
  const auto cluster = DecodeDecimal(p.substr(8, 2));
  if (!cluster) return Refuse(command.text, "03");
  if (*end > steps.last || *start < steps.first) return Refuse(command.text, "04");
  if (*end < *start) return Refuse(command.text, "05");
  ScanEcho echo;
  echo.request.type = command.scan_type;
  echo.request.start_step = *start;
  echo.request.end_step = *end;
  echo.request.cluster = *cluster;
  if (Info(command.scan_type).streaming) {
    const auto skip = DecodeDecimal(p.substr(10, 1));
    if (!skip) return Refuse(command.text, "06");
    const auto count = DecodeDecimal(p.substr(11, 2));
    if (!count) return Refuse(command.text, "07");
    echo.request.skip = *skip;
    echo.request.count = *count;
  }
  echo.tag = std::string(command.tag);
  return echo;
}

}  // namespace selfcal::scip
