// A helper program run to its end: found in PATH (spawn runs a program as given, never looking it
// up), started the project's one way (process/spawn.hpp) in the caller's process group, waited
// for with a bound and killed past it. What the CLI runs Graphviz's dot with, and the domain
// binutils' objcopy.
#pragma once

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>

#include <tl/expected.hpp>

#include "process/spawn.hpp"

namespace rsca::process {

// The first executable regular file `name` in PATH's folders (/usr/bin:/bin without PATH).
std::optional<std::filesystem::path> find_program(const std::string &name);

// Runs `command` until it exits, killing it past `timeout`; an error (why, naming the program)
// unless it exited with 0.
tl::expected<void, std::string> run_to_end(const Command &command,
                                           std::chrono::milliseconds timeout);

} // namespace rsca::process
