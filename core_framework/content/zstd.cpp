#include "content/zstd.hpp"

#include <memory>

#include <zstd.h>

#include <fmt/format.h>

namespace rsca::content {

namespace {

struct FreeContext {
  void operator()(ZSTD_CCtx *context) const { ZSTD_freeCCtx(context); }
};

} // namespace

// With a checksum of its content in the frame: a frame corrupted on the way fails to decompress
// rather than giving other bytes (the SHA-256 of the whole file would catch them, later).
Buffer zstd_compress(const std::uint8_t *data, std::size_t size, int level) {
  thread_local std::unique_ptr<ZSTD_CCtx, FreeContext> context(ZSTD_createCCtx());
  ZSTD_CCtx_reset(context.get(), ZSTD_reset_session_and_parameters);
  ZSTD_CCtx_setParameter(context.get(), ZSTD_c_compressionLevel, level);
  ZSTD_CCtx_setParameter(context.get(), ZSTD_c_checksumFlag, 1);
  Buffer out(ZSTD_compressBound(size));
  const std::size_t n = ZSTD_compress2(context.get(), out.data(), out.size(), data, size);
  if (ZSTD_isError(n) != 0U)
    return {}; // cannot happen with a bound-sized buffer; an empty frame is refused downstream
  out.resize(n);
  return out;
}

tl::expected<Buffer, std::string> zstd_decompress(const std::uint8_t *data, std::size_t size,
                                                  std::size_t expected, std::size_t limit) {
  if (expected > limit)
    return tl::unexpected(fmt::format("{} bytes expected, over the limit of {}", expected, limit));
  // The frame must be whole: exactly `size` bytes, no trailing data.
  const std::size_t frame = ZSTD_findFrameCompressedSize(data, size);
  if (ZSTD_isError(frame) != 0U || frame != size)
    return tl::unexpected(std::string("not one whole zstd frame"));
  const unsigned long long declared = ZSTD_getFrameContentSize(data, size);
  if (declared == ZSTD_CONTENTSIZE_ERROR || declared == ZSTD_CONTENTSIZE_UNKNOWN)
    return tl::unexpected(std::string("a zstd frame that does not declare its size"));
  if (declared != expected)
    return tl::unexpected(
        fmt::format("a zstd frame of {} bytes where {} were expected", declared, expected));
  // The output buffer is the bound: zstd writes no more than its capacity, and says so.
  Buffer out(expected);
  const std::size_t n = ZSTD_decompress(out.data(), out.size(), data, size);
  if (ZSTD_isError(n) != 0U)
    return tl::unexpected(fmt::format("a corrupt zstd frame: {}", ZSTD_getErrorName(n)));
  if (n != expected)
    return tl::unexpected(
        fmt::format("a zstd frame that held {} bytes where {} were expected", n, expected));
  return out;
}

} // namespace rsca::content
