#include "value_text.hpp"

#include <fmt/format.h>

namespace rsca::cli {
namespace {

// The first items shown of a summarised sequence.
constexpr std::size_t kShownItems = 3;

std::string summary(const nlohmann::json &value);

std::string summarised_text(const std::string &text) {
  if (text.size() <= kSummarisedChars)
    return text;
  return fmt::format("{}… {} chars", text.substr(0, kSummarisedChars / 2), text.size());
}

// Nested values (structs, sequences of structs) are summarised each.
std::string summary(const nlohmann::json &value) {
  if (value.is_array()) {
    std::string items;
    const std::size_t shown = value.size() > kSummarisedItems ? kShownItems : value.size();
    for (std::size_t i = 0; i < shown; ++i)
      items += (i > 0 ? ", " : "") + summary(value[i]);
    if (shown < value.size())
      items += fmt::format(", … {} values", value.size());
    return "[" + items + "]";
  }
  if (value.is_object()) {
    std::string members;
    for (const auto &[key, member] : value.items())
      members += fmt::format("{}\"{}\": {}", members.empty() ? "" : ", ", key, summary(member));
    return "{" + members + "}";
  }
  if (value.is_string())
    return nlohmann::json(summarised_text(value.get<std::string>())).dump();
  return value.dump();
}

} // namespace

std::string value_text(const nlohmann::json &value, bool full) {
  if (value.is_string())
    return full ? value.get<std::string>() : summarised_text(value.get<std::string>());
  return full ? value.dump() : summary(value);
}

} // namespace rsca::cli
