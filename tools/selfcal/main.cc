// `selfcal`: the command line of the selfcal project (simulate, calibrate offline, evaluate, ...).
#include <unistd.h>

#include <csignal>

#include "protocols/program/program.h"
#include "tools/selfcal/commands.h"

namespace {

// Ctrl-C or SIGTERM: say so instead of vanishing with exit 130. Every file selfcal writes is
// renamed into place whole, so what exists is complete; the command's output is not written.
void OnInterrupt(int signal) {
  constexpr char kMessage[] =
      "\nselfcal: interrupted; the command's output was not written (files already there are "
      "complete: every file is written whole or not at all)\n";
  [[maybe_unused]] const auto written = write(STDERR_FILENO, kMessage, sizeof(kMessage) - 1);
  _exit(128 + signal);
}

}  // namespace

int main(int argc, char** argv) {
  std::signal(SIGINT, OnInterrupt);
  std::signal(SIGTERM, OnInterrupt);
  selfcal::program::Program program(
      "selfcal",
      "selfcal: robot self-calibration with the 3D sensor the robot carries.\n"
      "Run 'selfcal <command> --help' for the options of a command.");
  program.app().set_version_flag("--version", std::string("selfcal ") + SELFCAL_VERSION);
  program.app().require_subcommand(1);
  program.app().fallthrough();                                // -q and -v after the command, too
  program.app().option_defaults()->always_capture_default();  // shown by --help
  selfcal::cli::RegisterAll(program.app());
  selfcal::cli::ShowDefaultsInHelp(program.app());
  if (auto exit = selfcal::cli::AnswerHelp(program.app(), argc, argv)) return *exit;
  if (auto exit = selfcal::cli::RefuseUnknownCommand(program.app(), argc, argv)) return *exit;
  if (auto exit = program.Parse(argc, argv)) return *exit;
  return selfcal::cli::exit_code;
}
