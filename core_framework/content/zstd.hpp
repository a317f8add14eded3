// zstd frames of file content on the wire (libzstd): the domain compresses each piece of a file a
// node fetches (domain/file_manager.hpp), the node decompresses it (node/package_fetch.cpp).
// Decompression is bounded: the bytes come from the network, and a small frame may claim or hold
// far more than a piece (a bomb), or be corrupt; either is refused, never allocated for.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <tl/expected.hpp>

namespace rsca::content {

using Buffer = std::vector<std::uint8_t>;

// One zstd frame of `data`, its content size and checksum in its header. Level 3, zstd's default:
// about 300 MB/s on one core, fast enough to do per piece as it is served.
Buffer zstd_compress(const std::uint8_t *data, std::size_t size, int level = 3);

// The `expected` bytes a frame holds: an error when it is not one whole zstd frame, when it
// declares or holds other than `expected` bytes (never more is written than that), or when
// `expected` is over `limit`.
tl::expected<Buffer, std::string> zstd_decompress(const std::uint8_t *data, std::size_t size,
                                                  std::size_t expected, std::size_t limit);

} // namespace rsca::content
