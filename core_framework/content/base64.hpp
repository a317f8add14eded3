// Base64 (RFC 4648, with padding) through OpenSSL's EVP: how code files travel inside an install
// request, whose JSON holds only text.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace rsca::content {

std::string base64_encode(std::string_view bytes);
// The bytes, or nullopt when `text` is not base64: a length not a multiple of 4, a character
// outside the alphabet, or padding anywhere but at the end.
std::optional<std::string> base64_decode(std::string_view text);
// How many bytes `text` decodes to, without decoding it; nullopt when it is not base64.
std::optional<std::size_t> base64_decoded_size(std::string_view text);

} // namespace rsca::content
