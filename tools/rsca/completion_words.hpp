// rsca completion words KIND...: the live names a completion offers (apps, installed applications,
// nodes, devices as NODE:DEVICE, channels), one a line, from the running domain. Quick and
// quiet: a domain that is not there, or slow, gives no names and exit 0, as a shell's completion
// must not print errors into the command line being typed.
#pragma once

#include <CLI/CLI.hpp>

#include "commands.hpp"

namespace rsca::cli {

// Registers `words` under `completion`.
void add_completion_words_command(CLI::App &completion, const GlobalOptions &global,
                                  int &exit_code);

} // namespace rsca::cli
