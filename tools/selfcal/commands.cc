#include "tools/selfcal/commands.h"

namespace selfcal::cli {

int exit_code = 0;

// One line per subcommand, in the order `selfcal --help` lists them.
void RegisterModelCheck(CLI::App& app);

void RegisterAll(CLI::App& app) {
  RegisterModelCheck(app);
}

}  // namespace selfcal::cli
