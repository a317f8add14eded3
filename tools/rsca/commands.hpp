// The rsca subcommands; each registers itself on the CLI11 app and runs when chosen.
#pragma once

#include <CLI/CLI.hpp>

namespace rsca::cli {

// Options every command shares.
struct GlobalOptions {
  bool json = false;
  std::string sdrroot;
  std::string domain = "rsca";
  int timeout_ms = 5000;
};

void add_validate_command(CLI::App &app, const GlobalOptions &global, int &exit_code);
void add_show_command(CLI::App &app, const GlobalOptions &global, int &exit_code);
void add_application_commands(CLI::App &app, const GlobalOptions &global, int &exit_code);
void add_ls_command(CLI::App &app, const GlobalOptions &global, int &exit_code);
void add_domain_command(CLI::App &app, const GlobalOptions &global, int &exit_code);
// rsca show APP when the argument is not a profile file.
int show_application(const std::string &name, const GlobalOptions &global);

} // namespace rsca::cli
