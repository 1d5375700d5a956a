// `selfcal`: the command line of the selfcal project (simulate, calibrate offline, evaluate, ...).
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <iostream>

#include "tools/selfcal/commands.h"

int main(int argc, char** argv) {
  CLI::App app{
      "selfcal: robot self-calibration with the 3D sensor the robot carries.\n"
      "Run 'selfcal <command> --help' for the options of a command."};
  app.set_version_flag("--version", std::string("selfcal ") + SELFCAL_VERSION);
  app.require_subcommand(1);
  bool verbose = false;
  bool quiet = false;
  app.add_flag("-v,--verbose", verbose, "Log debug messages");
  app.add_flag("-q,--quiet", quiet, "Log warnings and errors only");
  // Logs go to stderr so that stdout carries only results.
  spdlog::set_default_logger(spdlog::stderr_color_mt("selfcal"));
  app.parse_complete_callback([&] {
    spdlog::set_level(verbose ? spdlog::level::debug
                              : (quiet ? spdlog::level::warn : spdlog::level::info));
  });
  selfcal::cli::RegisterAll(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }
  return selfcal::cli::exit_code;
}
