#include "common/names.hpp"

#include <algorithm>
#include <cctype>

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

namespace {

// Levenshtein distance, letters compared without case (Freq and freq are one name to a reader).
std::size_t edit_distance(std::string_view a, std::string_view b) {
  const auto lower = [](char c) {
    return static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  };
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j)
    row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min(
          {row[j] + 1, row[j - 1] + 1, diagonal + (lower(a[i - 1]) == lower(b[j - 1]) ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

} // namespace

std::string closest_name(std::string_view name, const std::vector<std::string> &names) {
  // A third of the name's length, at least one and at most three edits: more reads as another name.
  const std::size_t most = std::clamp<std::size_t>(name.size() / 3, 1, 3);
  std::string best;
  std::size_t best_distance = most + 1;
  for (const auto &candidate : names)
    if (const auto d = edit_distance(name, candidate); d < best_distance) {
      best_distance = d;
      best = candidate;
    }
  return best;
}

} // namespace rsca
