// rsca: the command-line front end of the rsca domain.
#include <CLI/CLI.hpp>

#include "commands.hpp"
#include "exit_codes.hpp"

int main(int argc, char **argv) {
  CLI::App app{"rsca — deploy and manage component applications on a robot's domain"};
  app.require_subcommand(1);
  app.fallthrough(); // global options may follow the subcommand
  rsca::cli::GlobalOptions global;
  app.add_flag("--json", global.json, "Machine-readable JSON output");
  app.add_option("--sdrroot", global.sdrroot,
                 "SDR root where absolute profile paths resolve (default: the nearest folder "
                 "above each file that holds dom/ or dev/)");
  app.footer("Exit codes: 0 ok, 1 invalid profile, 2 usage error, 3 path not found.");

  int exit_code = rsca::cli::kOk;
  rsca::cli::add_validate_command(app, global, exit_code);
  rsca::cli::add_show_command(app, global, exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError &e) {
    int code = app.exit(e);
    return code == 0 ? rsca::cli::kOk : rsca::cli::kUsage;
  }
  return exit_code;
}
