#include "durations.hpp"

#include <limits>

#include <fmt/format.h>

#include "common/units.hpp"

namespace rsca::cli {

tl::expected<std::chrono::milliseconds, std::string> parse_cli_duration(std::string_view text) {
  // Minutes and hours on top of the profiles' units (common/units.hpp): "5m" is 5 × 60 s.
  std::string seconds(text);
  long long scale = 1;
  if (text.ends_with("h") || (text.ends_with("m") && !text.ends_with("ms") && text != "m")) {
    scale = text.back() == 'h' ? 3600 : 60;
    seconds.back() = 's';
  }
  auto duration = parse_duration(seconds);
  if (!duration)
    return tl::unexpected(fmt::format("\"{}\" is not a duration: give a number and a unit, e.g. "
                                      "500ms, 5s, 5m, 1h",
                                      text));
  if (duration->infinite() || duration->value->count() < 0)
    return tl::unexpected(fmt::format("\"{}\": a finite duration, not negative", text));
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(*duration->value) * scale;
  if (ms.count() > std::numeric_limits<int>::max())
    return tl::unexpected(fmt::format("\"{}\" is too long (at most about 24 days)", text));
  return ms;
}

void add_duration_option(CLI::App &command, const std::string &name, int &ms,
                         const std::string &help) {
  const std::string option = "--" + name;
  command.add_option_function<std::string>(
      option,
      [option, &ms](const std::string &text) {
        auto duration = parse_cli_duration(text);
        if (!duration)
          throw CLI::ValidationError(option, duration.error());
        ms = static_cast<int>(duration->count());
      },
      help + " (a duration: 500ms, 5s, 5m, 1h)");
  command.add_option(option + "-ms", ms, "The same in milliseconds (the old spelling)");
}

} // namespace rsca::cli
