// Small text helpers the profiles, the DDS configuration and the CLI share.
#pragma once

#include <string>
#include <string_view>

namespace rsca {

// `text` without the white space XML allows around a value (space, tab, CR, LF) at either end.
inline std::string_view trim(std::string_view text) {
  constexpr std::string_view kSpace = " \t\r\n";
  const auto first = text.find_first_not_of(kSpace);
  if (first == std::string_view::npos)
    return {};
  return text.substr(first, text.find_last_not_of(kSpace) - first + 1);
}

// Every occurrence of `key` in `text` replaced by `value` (a value holding the key is not
// replaced again).
inline void replace_all(std::string &text, std::string_view key, std::string_view value) {
  if (key.empty())
    return;
  for (auto at = text.find(key); at != std::string::npos; at = text.find(key, at + value.size()))
    text.replace(at, key.size(), value);
}

} // namespace rsca
