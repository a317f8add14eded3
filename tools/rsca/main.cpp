// rsca: the command-line front end of the rsca domain.
//
// One name per idea across the commands: -o/--out is where a command writes what it makes (a
// picture, a project; --output and --dir stay as aliases); --run-dir is the folder a local domain
// lives in (its pid files, logs, sockets), which `domain up` makes and `domain down` reads, not an
// output. A duration is a number and a unit (500ms, 5s, 5m, 1h: durations.hpp) under the idea's
// name (--timeout, --wait, --since); an option of the old spelling, --NAME-ms, stays as an alias.
// --json makes every command print JSON, and its failures {"error": {...}, "exit": CODE}.
#include <algorithm>
#include <cstring>
#include <string>

#include <CLI/CLI.hpp>

#include "commands.hpp"
#include "domain_client.hpp"
#include "durations.hpp"
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
  rsca::cli::add_duration_option(app, "timeout", global.timeout_ms,
                                 "Timeout of each request to the domain (default 5s)");
  app.footer(
      "Exit codes: 0 ok, 1 invalid profile or request, 2 usage error (also a local file error,\n"
      "e.g. `new` over an existing folder), 3 not found, 4 domain unreachable, 5 rejected by\n"
      "the domain, 6 failed (e.g. a launch, rolled back). With --json a failure prints\n"
      "{\"error\": {\"status\", \"message\"}, \"exit\": CODE}.\n"
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
  rsca::cli::add_echo_commands(app, global, exit_code);
  rsca::cli::add_domain_command(app, global, exit_code);
  rsca::cli::add_new_command(app, global, exit_code);
  rsca::cli::add_completion_command(app, global, exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError &e) {
    // --json may not have been read yet when the parse failed: looked for among the words.
    const bool json = global.json || std::any_of(argv + 1, argv + argc, [](const char *word) {
                        return std::strcmp(word, "--json") == 0;
                      });
    if (e.get_exit_code() == 0 || !json) {
      const int code = app.exit(e);
      return code == 0 ? rsca::cli::kOk : rsca::cli::kUsage;
    }
    global.json = true;
    return rsca::cli::fail(global, "", rsca::cli::kUsage, e.what());
  }
  return exit_code;
}
