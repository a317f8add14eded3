#include "common/cpu_list.hpp"
#include "common/text.hpp"

#include <algorithm>
#include <charconv>
#include <set>

#include <fmt/format.h>

namespace rsca {
namespace {

tl::expected<unsigned, std::string> number(std::string_view text) {
  text = trim(text);
  unsigned value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size())
    return tl::unexpected(fmt::format("\"{}\" is not a CPU number", text));
  if (value > kMaxCpuIndex)
    return tl::unexpected(fmt::format("{} is above {}", value, kMaxCpuIndex));
  return value;
}

} // namespace

tl::expected<std::vector<unsigned>, std::string> parse_cpu_list(std::string_view text) {
  if (trim(text).empty())
    return tl::unexpected(std::string("the list is empty"));
  std::set<unsigned> numbers;
  while (!text.empty()) {
    const auto comma = text.find(',');
    const std::string_view item = text.substr(0, comma);
    text = comma == std::string_view::npos ? std::string_view{} : text.substr(comma + 1);
    const auto dash = item.find('-');
    auto first = number(item.substr(0, dash));
    if (!first)
      return tl::unexpected(first.error());
    auto last = dash == std::string_view::npos ? first : number(item.substr(dash + 1));
    if (!last)
      return tl::unexpected(last.error());
    if (*last < *first)
      return tl::unexpected(fmt::format("the range \"{}\" runs backwards", trim(item)));
    for (unsigned n = *first; n <= *last; ++n)
      numbers.insert(n);
  }
  return std::vector<unsigned>(numbers.begin(), numbers.end());
}

} // namespace rsca
