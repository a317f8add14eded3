#include "content/base64.hpp"

#include <openssl/evp.h>

#include <algorithm>

namespace rsca::content {

namespace {

const unsigned char *bytes_of(std::string_view s) {
  return reinterpret_cast<const unsigned char *>(s.data());
}

unsigned char *bytes_of(std::string &s) {
  return reinterpret_cast<unsigned char *>(s.data());
}

bool alphabet(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '+' ||
         c == '/';
}

// EVP_DecodeBlock skips white space and takes '=' inside the text: refuse what RFC 4648 does.
bool well_formed(std::string_view text) {
  if (text.size() % 4 != 0)
    return false;
  const auto padding = text.find('=');
  const std::string_view data = text.substr(0, padding);
  if (padding != std::string_view::npos &&
      (text.size() - padding > 2 || text.find_first_not_of('=', padding) != std::string_view::npos))
    return false;
  return std::all_of(data.begin(), data.end(), alphabet);
}

} // namespace

std::string base64_encode(std::string_view bytes) {
  std::string out(4 * ((bytes.size() + 2) / 3), '\0');
  // OpenSSL takes an int length: an install's files are bounded far below that.
  const int written =
      EVP_EncodeBlock(bytes_of(out), bytes_of(bytes), static_cast<int>(bytes.size()));
  out.resize(static_cast<std::size_t>(std::max(written, 0)));
  return out;
}

std::optional<std::string> base64_decode(std::string_view text) {
  if (!well_formed(text))
    return std::nullopt;
  std::string out(3 * (text.size() / 4), '\0');
  const int written = EVP_DecodeBlock(bytes_of(out), bytes_of(text), static_cast<int>(text.size()));
  if (written < 0)
    return std::nullopt;
  // EVP_DecodeBlock counts the padding's bytes as data: drop one per '='.
  const auto padding = static_cast<std::size_t>(
      std::count(text.end() - std::min<std::size_t>(2, text.size()), text.end(), '='));
  out.resize(static_cast<std::size_t>(written) - padding);
  return out;
}

} // namespace rsca::content
