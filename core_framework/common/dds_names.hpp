// Names that go into DDS topic names: letters and digits kept, anything else an underscore, so
// that an application, channel or domain name never makes an invalid or ambiguous topic name.
#pragma once

#include <cctype>
#include <string>
#include <string_view>

namespace rsca {

inline std::string dds_name(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text)
    out += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return out;
}

} // namespace rsca
