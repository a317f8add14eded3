#include "common/names.hpp"

#include <fmt/format.h>

namespace rsca {
namespace {

bool is_control(unsigned char c) {
  return c < 0x20 || c == 0x7f;
}

tl::unexpected<Error> name_error(std::string_view what, std::string message) {
  return make_error({std::string(what), 0, 0}, "name", std::move(message));
}

// The end of the UTF-8 sequences within the first `max` bytes: a cut at `max` may fall inside
// one, whose continuation bytes (10xxxxxx) are then left out with it.
std::size_t utf8_cut(std::string_view text, std::size_t max) {
  std::size_t cut = max;
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80)
    --cut;
  return cut;
}

} // namespace

std::string excerpt(std::string_view text, std::size_t max) {
  const bool cut = text.size() > max;
  const std::string_view shown = cut ? text.substr(0, utf8_cut(text, max)) : text;
  std::string out;
  out.reserve(shown.size() + 24);
  for (char c : shown)
    if (is_control(static_cast<unsigned char>(c)))
      out += fmt::format("\\x{:02x}", static_cast<unsigned char>(c));
    else
      out += c;
  if (cut)
    out += fmt::format("... ({} bytes)", text.size());
  return out;
}

Expected<void> check_name(std::string_view what, std::string_view name) {
  if (name.empty())
    return name_error(what, fmt::format("{} has no name", what));
  if (name.size() > kMaxNameLength)
    return name_error(what, fmt::format("{} \"{}\" is too long a name: at most {} bytes", what,
                                        excerpt(name), kMaxNameLength));
  auto refuse = [&](std::string_view why) {
    return name_error(what, fmt::format("{} \"{}\" is not a name: {}", what, excerpt(name), why));
  };
  if (name == "." || name == "..")
    return refuse("it names a folder");
  if (name.front() == '.')
    return refuse("it starts with '.'");
  for (char c : name) {
    if (c == '/' || c == '\\')
      return refuse(fmt::format("it holds a '{}'", c));
    if (is_control(static_cast<unsigned char>(c)))
      return refuse("it holds a control character");
  }
  return {};
}

} // namespace rsca
