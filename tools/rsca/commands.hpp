// The rsca subcommands; each registers itself on the CLI11 app and runs when chosen.
#pragma once

#include <CLI/CLI.hpp>

namespace rsca::cli {

// Options every command shares.
struct GlobalOptions {
  bool json = false;
  std::string sdrroot;
};

void add_validate_command(CLI::App &app, const GlobalOptions &global, int &exit_code);
void add_show_command(CLI::App &app, const GlobalOptions &global, int &exit_code);

} // namespace rsca::cli
