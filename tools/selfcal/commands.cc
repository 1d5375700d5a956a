#include "tools/selfcal/commands.h"

#include <algorithm>
#include <iostream>
#include <string>
#include <vector>

#include "tools/selfcal/cli_util.h"

namespace selfcal::cli {

int exit_code = 0;

// One declaration and one call per subcommand, in blocks per area so that parallel work does
// not touch the same lines.
void RegisterModelCheck(CLI::App& app);
// --- kinematics ---
void RegisterFk(CLI::App& app);
void RegisterEvaluate(CLI::App& app);
void RegisterExport(CLI::App& app);
void RegisterImport(CLI::App& app);
// --- simulation ---
void RegisterSimulate(CLI::App& app);
// --- calibration ---
void RegisterCalibrate(CLI::App& app);
void RegisterReport(CLI::App& app);
// --- daemon client ---
void RegisterTrigger(CLI::App& app);
void RegisterStatus(CLI::App& app);
void RegisterAbort(CLI::App& app);
void RegisterHistory(CLI::App& app);
void RegisterRollback(CLI::App& app);
void RegisterDaemonPlan(CLI::App& app);
// --- planning ---
void RegisterPlan(CLI::App& app);

void RegisterAll(CLI::App& app) {
  RegisterModelCheck(app);
  // --- kinematics ---
  RegisterFk(app);
  RegisterEvaluate(app);
  RegisterExport(app);
  RegisterImport(app);
  // --- simulation ---
  RegisterSimulate(app);
  // --- calibration ---
  RegisterCalibrate(app);
  RegisterReport(app);
  // --- daemon client ---
  RegisterTrigger(app);
  RegisterStatus(app);
  RegisterAbort(app);
  RegisterHistory(app);
  RegisterRollback(app);
  RegisterDaemonPlan(app);
  // --- planning ---
  RegisterPlan(app);
}

namespace {

// Edits (insert, delete, replace, swap two neighbours) from `a` to `b`: optimal string alignment.
std::size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[a.size()][b.size()];
}

// The command nearest to `word`, by the whole name or one of its dash-separated parts ("plna"
// is one swap from the "plan" of daemon-plan, and from plan itself, which wins the tie); empty
// when none is within a typo's reach.
std::string NearestCommand(CLI::App& app, const std::string& word) {
  const std::size_t reach = word.size() < 5 ? 1 : 2;
  std::string nearest;
  std::size_t best = reach + 1;
  bool nearest_whole = false;
  for (const CLI::App* command : app.get_subcommands([](CLI::App*) { return true; })) {
    const std::string name = command->get_name();
    std::vector<std::string> forms{name};
    for (std::size_t start = 0, dash; (dash = name.find('-', start)) != std::string::npos;
         start = dash + 1) {
      forms.push_back(name.substr(start, dash - start));
      forms.push_back(name.substr(dash + 1));
    }
    for (const std::string& form : forms) {
      const std::size_t distance = EditDistance(word, form);
      // On a tie a whole name wins over a part ("plna": plan, not daemon-plan).
      if (distance < best || (distance == best && form == name && !nearest_whole)) {
        best = distance;
        nearest = name;
        nearest_whole = form == name;
      }
    }
  }
  return nearest;
}

int RefuseWord(CLI::App& app, const std::string& word) {
  const std::string nearest = NearestCommand(app, word);
  return Fail("unknown command '" + word + "'" +
                  (nearest.empty() ? "" : " (did you mean '" + nearest + "'?)") + "; run '" +
                  app.get_name() + " --help' for the list",
              program::kExitUsage);
}

CLI::App* CommandNamed(CLI::App& app, const std::string& word) {
  for (CLI::App* command : app.get_subcommands([](CLI::App*) { return true; })) {
    if (command->check_name(word)) return command;
  }
  return nullptr;
}

// The words of the command line that are no options: the options before a command (-v, -q,
// --help, --version) take no value.
std::vector<std::string> Words(int argc, char** argv) {
  std::vector<std::string> words;
  for (int i = 1; i < argc; ++i) {
    if (argv[i][0] != '\0' && argv[i][0] != '-') words.emplace_back(argv[i]);
  }
  return words;
}

bool AsksForHelpOrVersion(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string option = argv[i];
    if (option == "-h" || option == "--help" || option == "--version") return true;
  }
  return false;
}

}  // namespace

void ShowDefaultsInHelp(CLI::App& app) {
  for (CLI::Option* option : app.get_options()) {
    const std::string& shown = option->get_default_str();
    if (shown == "-1" || shown == "[]" ||
        option->get_description().find("default") != std::string::npos) {
      option->default_str("");
    }
  }
  for (CLI::App* command : app.get_subcommands([](CLI::App*) { return true; })) {
    ShowDefaultsInHelp(*command);
  }
}

std::optional<int> RefuseUnknownCommand(CLI::App& app, int argc, char** argv) {
  const std::vector<std::string> words = Words(argc, argv);
  if (words.empty()) return std::nullopt;
  if (CommandNamed(app, words.front())) return std::nullopt;
  return RefuseWord(app, words.front());
}

std::optional<int> AnswerHelp(CLI::App& app, int argc, char** argv) {
  const std::vector<std::string> words = Words(argc, argv);
  if (words.empty()) {
    if (AsksForHelpOrVersion(argc, argv)) return std::nullopt;
    std::cerr << "error: a command is required\n\n" << app.help();
    return program::kExitUsage;
  }
  if (words.front() != "help") return std::nullopt;
  if (words.size() == 1) {
    std::cout << app.help();
    return 0;
  }
  CLI::App* command = CommandNamed(app, words[1]);
  if (!command) return RefuseWord(app, words[1]);
  std::cout << command->help(app.get_name());
  return 0;
}

}  // namespace selfcal::cli
