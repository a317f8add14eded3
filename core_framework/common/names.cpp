#include "common/names.hpp"

#include <algorithm>

#include <fmt/format.h>

namespace rsca {
namespace {

bool is_control(char c) {
  const auto u = static_cast<unsigned char>(c);
  return u < 0x20 || u == 0x7f;
}

} // namespace

tl::expected<void, std::string> check_name(std::string_view what, std::string_view name) {
  auto refuse = [&](std::string_view why) {
    return tl::unexpected(fmt::format("{} \"{}\" is not a name: {}", what, excerpt(name), why));
  };
  if (name.empty())
    return tl::unexpected(fmt::format("{} is empty", what));
  if (name.size() > kMaxNameLength)
    return refuse(fmt::format("{} bytes long, at most {}", name.size(), kMaxNameLength));
  if (name == "." || name == "..")
    return refuse("it names a folder, not an application");
  if (name.front() == '.')
    return refuse("it starts with '.'");
  if (name.find_first_of("/\\") != std::string_view::npos)
    return refuse("it holds a path separator ('/' or '\\')");
  if (std::any_of(name.begin(), name.end(), is_control))
    return refuse("it holds a control character");
  return {};
}

std::string excerpt(std::string_view text, std::size_t max) {
  std::string out;
  const std::size_t shown = std::min(text.size(), max);
  out.reserve(shown + 32);
  for (char c : text.substr(0, shown))
    out += is_control(c) ? '?' : c;
  if (text.size() > max)
    out += fmt::format("... ({} bytes)", text.size());
  return out;
}

} // namespace rsca
