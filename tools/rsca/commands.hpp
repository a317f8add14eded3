// The rsca subcommands; each registers itself on the CLI11 app and runs when chosen.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

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
void add_plan_command(CLI::App &app, const GlobalOptions &global, int &exit_code);
void add_events_command(CLI::App &app, const GlobalOptions &global, int &exit_code);
void add_new_command(CLI::App &app, const GlobalOptions &global, int &exit_code);
void add_top_command(CLI::App &app, const GlobalOptions &global, int &exit_code);
void add_logs_command(CLI::App &app, const GlobalOptions &global, int &exit_code);
// rsca echo and rsca hz: a port's samples as they flow, and their rate (echo_command.cpp).
void add_echo_commands(CLI::App &app, const GlobalOptions &global, int &exit_code);
// rsca completion bash|zsh: made from `app`'s commands, so register it after them.
void add_completion_command(CLI::App &app, const GlobalOptions &global, int &exit_code);

// Installs the application of `sad` in the domain; its installed name goes to `installed_name`
// (and nothing is printed in --json mode) when given. An exit code.
int install(const std::string &sad, const std::string &name, const GlobalOptions &global,
            std::string *installed_name = nullptr);
// --assign COMPONENT=DEVICE arguments; nullopt (after saying why) when malformed.
std::optional<std::map<std::string, std::string>>
assignments_of(const std::vector<std::string> &assignments, const char *command);

// rsca show APP when the argument is not a profile file.
int show_application(const std::string &name, const GlobalOptions &global);

// rsca show APP --graph FORMAT [-o OUTPUT].
struct GraphOptions {
  std::string format; // "dot" or "svg"; empty: no picture
  std::string output; // empty: stdout
};
// The running application's picture (show_graph.cpp).
int show_application_graph(const std::string &name, const GraphOptions &options,
                           const GlobalOptions &global);

} // namespace rsca::cli
