// Base64 as an install carries code: RFC 4648's vectors both ways, and text that is not base64
// refused rather than decoded to something.
#include <catch2/catch.hpp>

#include "content/base64.hpp"

using rsca::content::base64_decode;
using rsca::content::base64_encode;

TEST_CASE("base64 encodes and decodes RFC 4648's test vectors", "[unit][base64]") {
  const std::pair<std::string, std::string> vectors[] = {{"", ""},
                                                         {"f", "Zg=="},
                                                         {"fo", "Zm8="},
                                                         {"foo", "Zm9v"},
                                                         {"foob", "Zm9vYg=="},
                                                         {"fooba", "Zm9vYmE="},
                                                         {"foobar", "Zm9vYmFy"}};
  for (const auto &[plain, encoded] : vectors) {
    CHECK(base64_encode(plain) == encoded);
    CHECK(base64_decode(encoded) == plain);
  }
}

TEST_CASE("base64 carries every byte value", "[unit][base64]") {
  std::string bytes;
  for (int i = 0; i < 256; ++i)
    bytes.push_back(static_cast<char>(i));
  const auto back = base64_decode(base64_encode(bytes));
  REQUIRE(back.has_value());
  CHECK(*back == bytes);
}

TEST_CASE("text that is not base64 is refused", "[unit][base64]") {
  // Each of a length base64 allows, so that the alphabet and the padding are what is judged.
  for (const char *bad : {"Zg=", "Zm\n9", "Zm 9", "Zm9!", "Z===", "Zg==Zg==", "=Zm9", "Zg=A"})
    CHECK_FALSE(base64_decode(bad).has_value());
}

TEST_CASE("base64's decoded size is known before decoding", "[unit][base64]") {
  using rsca::content::base64_decoded_size;
  CHECK(base64_decoded_size("") == 0U);
  CHECK(base64_decoded_size("Zg==") == 1U);
  CHECK(base64_decoded_size("Zm8=") == 2U);
  CHECK(base64_decoded_size("Zm9vYmFy") == 6U);
  CHECK_FALSE(base64_decoded_size("Zm9").has_value());
  // Across the pieces OpenSSL is given (4 MiB of text each): the size and the bytes still agree.
  const std::string big((3U << 20U) + 7, '\x5a');
  const auto text = base64_encode(big);
  CHECK(base64_decoded_size(text) == big.size());
  CHECK(base64_decode(text) == big);
}
