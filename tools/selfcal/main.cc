// `selfcal`: the command line of the selfcal project (simulate, calibrate offline, evaluate, ...).
#include "protocols/program/program.h"
#include "tools/selfcal/commands.h"

int main(int argc, char** argv) {
  selfcal::program::Program program(
      "selfcal",
      "selfcal: robot self-calibration with the 3D sensor the robot carries.\n"
      "Run 'selfcal <command> --help' for the options of a command.");
  program.app().set_version_flag("--version", std::string("selfcal ") + SELFCAL_VERSION);
  program.app().require_subcommand(1);
  program.app().fallthrough();  // -q and -v after the command, too
  selfcal::cli::RegisterAll(program.app());
  if (auto exit = selfcal::cli::AnswerHelp(program.app(), argc, argv)) return *exit;
  if (auto exit = selfcal::cli::RefuseUnknownCommand(program.app(), argc, argv)) return *exit;
  if (auto exit = program.Parse(argc, argv)) return *exit;
  return selfcal::cli::exit_code;
}
