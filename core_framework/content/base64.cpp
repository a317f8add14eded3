#include "content/base64.hpp"

#include <openssl/evp.h>

#include <algorithm>

namespace rsca::content {

namespace {

// OpenSSL's EVP block functions take an int length: text goes through them in pieces, each a
// whole number of base64 quanta (3 bytes, 4 characters).
constexpr std::size_t kBytesPerPiece = 3U << 20U;
constexpr std::size_t kCharsPerPiece = 4U << 20U;

const unsigned char *bytes_of(std::string_view s) {
  return reinterpret_cast<const unsigned char *>(s.data());
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

std::size_t padding_of(std::string_view text) {
  return static_cast<std::size_t>(
      std::count(text.end() - static_cast<std::ptrdiff_t>(std::min<std::size_t>(2, text.size())),
                 text.end(), '='));
}

} // namespace

std::string base64_encode(std::string_view bytes) {
  std::string out;
  out.reserve(4 * ((bytes.size() + 2) / 3));
  for (std::size_t at = 0; at < bytes.size(); at += kBytesPerPiece) {
    const std::string_view piece = bytes.substr(at, kBytesPerPiece);
    std::string encoded(4 * ((piece.size() + 2) / 3), '\0');
    EVP_EncodeBlock(reinterpret_cast<unsigned char *>(encoded.data()), bytes_of(piece),
                    static_cast<int>(piece.size()));
    out += encoded;
  }
  return out;
}

std::optional<std::size_t> base64_decoded_size(std::string_view text) {
  if (!well_formed(text))
    return std::nullopt;
  return text.size() / 4 * 3 - padding_of(text);
}

std::optional<std::string> base64_decode(std::string_view text) {
  const auto size = base64_decoded_size(text);
  if (!size)
    return std::nullopt;
  std::string out;
  out.reserve(*size);
  for (std::size_t at = 0; at < text.size(); at += kCharsPerPiece) {
    const std::string_view piece = text.substr(at, kCharsPerPiece);
    std::string decoded(3 * (piece.size() / 4), '\0');
    if (EVP_DecodeBlock(reinterpret_cast<unsigned char *>(decoded.data()), bytes_of(piece),
                        static_cast<int>(piece.size())) < 0)
      return std::nullopt;
    out += decoded;
  }
  // EVP_DecodeBlock counts the padding's bytes as data (they are in the last piece).
  out.resize(*size);
  return out;
}

} // namespace rsca::content
