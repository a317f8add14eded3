// One syntax for every duration the CLI takes: a number and a unit, e.g. 500ms, 5s, 5m, 1h (also
// us and ns). Each option that takes one is --NAME; an option of the old spelling, --NAME-ms with
// a bare number of milliseconds, stays as its alias.
#pragma once

#include <chrono>
#include <string>
#include <string_view>

#include <CLI/CLI.hpp>
#include <tl/expected.hpp>

namespace rsca::cli {

// `text` as a duration (finite, not negative), in milliseconds (rounded down).
tl::expected<std::chrono::milliseconds, std::string> parse_cli_duration(std::string_view text);

// Adds --NAME taking a duration and its alias --NAME-ms taking milliseconds, both into `ms`.
void add_duration_option(CLI::App &command, const std::string &name, int &ms,
                         const std::string &help);

} // namespace rsca::cli
