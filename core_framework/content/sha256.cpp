#include "content/sha256.hpp"

#include <array>
#include <cerrno>
#include <cstring>

#include <fcntl.h>
#include <unistd.h>

#include <fmt/format.h>
#include <openssl/evp.h>

#include "process/fd.hpp"

namespace rsca::content {

struct Sha256::Context {
  struct Free {
    void operator()(EVP_MD_CTX *c) const { EVP_MD_CTX_free(c); }
  };
  std::unique_ptr<EVP_MD_CTX, Free> md{EVP_MD_CTX_new()};
};

Sha256::Sha256() : context_(std::make_unique<Context>()) {
  // Only allocation fails here; OpenSSL's default provider always has SHA-256.
  if (!context_->md || EVP_DigestInit_ex(context_->md.get(), EVP_sha256(), nullptr) != 1)
    throw std::bad_alloc();
}

Sha256::~Sha256() = default;
Sha256::Sha256(Sha256 &&) noexcept = default;
Sha256 &Sha256::operator=(Sha256 &&) noexcept = default;

void Sha256::update(const void *data, std::size_t size) {
  EVP_DigestUpdate(context_->md.get(), data, size);
}

std::string Sha256::final_hex() {
  std::array<unsigned char, EVP_MAX_MD_SIZE> digest{};
  unsigned int length = 0;
  EVP_DigestFinal_ex(context_->md.get(), digest.data(), &length);
  std::string hex;
  hex.reserve(2 * length);
  for (unsigned i = 0; i < length; ++i)
    hex += fmt::format("{:02x}", digest[i]);
  return hex;
}

std::string sha256_hex(std::string_view bytes) {
  Sha256 hash;
  hash.update(bytes);
  return hash.final_hex();
}

Expected<std::string> sha256_of_file(const std::filesystem::path &file) {
  process::Fd fd(::open(file.c_str(), O_RDONLY | O_CLOEXEC));
  if (!fd)
    return make_error({file.string(), 0, 0}, "read", std::strerror(errno));
  Sha256 hash;
  std::array<char, 1 << 16> block{};
  for (;;) {
    const ssize_t n = ::read(fd.get(), block.data(), block.size());
    if (n == 0)
      return hash.final_hex();
    if (n < 0 && errno == EINTR)
      continue;
    if (n < 0)
      return make_error({file.string(), 0, 0}, "read", std::strerror(errno));
    hash.update(block.data(), static_cast<std::size_t>(n));
  }
}

} // namespace rsca::content
