// rsca: the command-line front end of the rsca domain.
#include <string>

#include <CLI/CLI.hpp>

#include "commands.hpp"
#include "exit_codes.hpp"

int main(int argc, char **argv) {
  CLI::App app{"rsca — deploy and manage component applications on a robot's domain"};
  app.require_subcommand(1);
  app.fallthrough(); // global options may follow the subcommand
  app.set_version_flag("--version", std::string("rsca ") + RSCA_VERSION);
  rsca::cli::GlobalOptions global;
  app.add_flag("--json", global.json, "Machine-readable JSON output");
  app.add_option("--sdrroot", global.sdrroot,
                 "SDR root where absolute profile paths resolve (default: the nearest folder "
                 "above each file that holds dom/ or dev/)");
  app.add_option("--domain", global.domain, "The domain's name")->capture_default_str();
  app.add_option("--timeout-ms", global.timeout_ms, "Timeout of each request to the domain")
      ->capture_default_str();
  app.footer(
      "Exit codes: 0 ok, 1 invalid profile or request, 2 usage error, 3 not found,\n"
      "4 domain unreachable, 5 rejected by the domain, 6 failed (e.g. a launch, rolled back).\n"
      "The DDS domain is chosen with RSCA_DDS_DOMAIN (default 0).");

  int exit_code = rsca::cli::kOk;
  rsca::cli::add_validate_command(app, global, exit_code);
  rsca::cli::add_show_command(app, global, exit_code);
  rsca::cli::add_application_commands(app, global, exit_code);
  rsca::cli::add_plan_command(app, global, exit_code);
  rsca::cli::add_events_command(app, global, exit_code);
  rsca::cli::add_ls_command(app, global, exit_code);
  rsca::cli::add_top_command(app, global, exit_code);
  rsca::cli::add_logs_command(app, global, exit_code);
  rsca::cli::add_domain_command(app, global, exit_code);
  rsca::cli::add_new_command(app, global, exit_code);
  rsca::cli::add_completion_command(app, global, exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError &e) {
    int code = app.exit(e);
    return code == 0 ? rsca::cli::kOk : rsca::cli::kUsage;
  }
  return exit_code;
}
