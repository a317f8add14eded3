// zstd frames as delivered files travel (content/zstd.hpp): the bytes come back whole, and what
// the network may send instead, a frame that holds or claims more than a piece (a bomb), a corrupt
// or cut frame, trailing bytes, is refused without allocating for it.
#include <catch2/catch.hpp>

#include "content/zstd.hpp"

using Catch::Matchers::Contains;
using rsca::content::Buffer;
using rsca::content::zstd_compress;
using rsca::content::zstd_decompress;

namespace {

constexpr std::size_t kPiece = 1U << 20U;

Buffer text(std::size_t n) {
  Buffer b(n);
  for (std::size_t i = 0; i < n; ++i)
    b[i] = static_cast<std::uint8_t>("rsca delivers code "[i % 19] + (i / 4096) % 3);
  return b;
}

} // namespace

TEST_CASE("zstd: a piece comes back as it was, in fewer bytes", "[unit][zstd]") {
  const Buffer plain = text(kPiece);
  const Buffer frame = zstd_compress(plain.data(), plain.size());
  CHECK(frame.size() < plain.size() / 4);
  auto back = zstd_decompress(frame.data(), frame.size(), plain.size(), kPiece);
  REQUIRE(back.has_value());
  CHECK(*back == plain);
}

TEST_CASE("zstd: a bomb (a small frame of far more than a piece) is refused", "[unit][zstd]") {
  const Buffer zeros(64U * kPiece, 0);
  const Buffer bomb = zstd_compress(zeros.data(), zeros.size());
  REQUIRE(bomb.size() < 16 * 1024);
  // As a piece of 1 MiB: the frame declares 64 MiB.
  auto as_piece = zstd_decompress(bomb.data(), bomb.size(), kPiece, kPiece);
  REQUIRE_FALSE(as_piece.has_value());
  CHECK_THAT(as_piece.error(), Contains("67108864 bytes where 1048576"));
  // Asked for all of it: over the limit, refused before anything is allocated.
  auto whole = zstd_decompress(bomb.data(), bomb.size(), zeros.size(), kPiece);
  REQUIRE_FALSE(whole.has_value());
  CHECK_THAT(whole.error(), Contains("over the limit"));
}

TEST_CASE("zstd: a corrupt, cut or padded frame is refused", "[unit][zstd]") {
  const Buffer plain = text(100000);
  const Buffer frame = zstd_compress(plain.data(), plain.size());
  SECTION("a byte changed in its blocks") {
    Buffer bad = frame;
    for (std::size_t i = 20; i < bad.size(); i += 97)
      bad[i] ^= 0x5aU;
    auto back = zstd_decompress(bad.data(), bad.size(), plain.size(), kPiece);
    // Whatever zstd makes of it, it is never taken as the piece.
    CHECK_FALSE((back.has_value() && *back == plain));
    CHECK_FALSE(back.has_value());
  }
  SECTION("cut short") {
    auto back = zstd_decompress(frame.data(), frame.size() / 2, plain.size(), kPiece);
    REQUIRE_FALSE(back.has_value());
    CHECK_THAT(back.error(), Contains("not one whole zstd frame"));
  }
  SECTION("bytes after the frame") {
    Buffer padded = frame;
    padded.push_back(0);
    auto back = zstd_decompress(padded.data(), padded.size(), plain.size(), kPiece);
    REQUIRE_FALSE(back.has_value());
    CHECK_THAT(back.error(), Contains("not one whole zstd frame"));
  }
  SECTION("not zstd at all") {
    auto back = zstd_decompress(plain.data(), 1000, 1000, kPiece);
    REQUIRE_FALSE(back.has_value());
  }
  SECTION("declaring other than the piece asked for") {
    auto back = zstd_decompress(frame.data(), frame.size(), plain.size() - 1, kPiece);
    REQUIRE_FALSE(back.has_value());
    CHECK_THAT(back.error(), Contains("100000 bytes where 99999"));
  }
}
