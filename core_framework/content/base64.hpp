// Base64 (RFC 4648, with padding, no line breaks) through OpenSSL: how file content travels in
// the control plane's JSON bodies (protocol/file_ops.hpp).
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace rsca::content {

std::string base64_encode(std::string_view bytes);
// The bytes `text` encodes; none when it is not base64.
std::optional<std::string> base64_decode(std::string_view text);

} // namespace rsca::content
