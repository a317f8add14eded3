#include "protocol/json_text.hpp"

#include <cstring>

#include <fmt/format.h>

namespace rsca::protocol {

namespace {

// Where the string opened by the quote at `open` ends (its closing quote: one after an even
// number of backslashes), or npos. memchr finds quotes far faster than a loop over the bytes.
std::size_t string_end(std::string_view text, std::size_t open) {
  std::size_t from = open + 1;
  for (;;) {
    const void *quote = std::memchr(text.data() + from, '"', text.size() - from);
    if (quote == nullptr)
      return std::string_view::npos;
    const auto at = static_cast<std::size_t>(static_cast<const char *>(quote) - text.data());
    std::size_t escapes = 0;
    while (at - escapes > open + 1 && text[at - escapes - 1] == '\\')
      ++escapes;
    if (escapes % 2 == 0)
      return at;
    from = at + 1;
  }
}

} // namespace

bool nests_deeper(std::string_view text, std::size_t max_depth) {
  std::size_t depth = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    switch (text[i]) {
    case '"':
      i = string_end(text, i);
      if (i == std::string_view::npos) // unterminated: not JSON, which the parse says
        return false;
      break;
    case '[':
    case '{':
      if (++depth > max_depth)
        return true;
      break;
    case ']':
    case '}':
      if (depth > 0) // unbalanced: not JSON, which the parse says
        --depth;
      break;
    default:
      break;
    }
  }
  return false;
}

tl::expected<Json, std::string> parse_json(std::string_view text, std::size_t max_depth) {
  // The scan first: cheaper than a parse callback on every value, and the parse then builds
  // nothing deeper than the bound.
  if (text.size() > kMaxJsonBytes)
    return tl::unexpected(
        fmt::format("is {} bytes, over the limit of {}", text.size(), kMaxJsonBytes));
  if (nests_deeper(text, max_depth))
    return tl::unexpected(fmt::format("nests deeper than {} levels", max_depth));
  try {
    return Json::parse(text);
  } catch (const Json::parse_error &e) {
    // Its "last read" may quote a whole long token: the reason is kept short.
    constexpr std::size_t kMaxReason = 240;
    return tl::unexpected(
        fmt::format("not valid JSON: {}", std::string_view(e.what()).substr(0, kMaxReason)));
  }
}

Json parse_json_pruned(std::string_view text, std::size_t max_depth) {
  // The callback's depth for an array or object starting is the number of those around it; one
  // it refuses is not built, nor is anything inside it.
  const auto keep = [max_depth](int depth, Json::parse_event_t event, Json &) {
    const bool starts =
        event == Json::parse_event_t::object_start || event == Json::parse_event_t::array_start;
    return !starts || static_cast<std::size_t>(depth) < max_depth;
  };
  return Json::parse(text, keep, /*allow_exceptions=*/false);
}

} // namespace rsca::protocol
