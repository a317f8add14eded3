// Content hashes: SHA-256 (OpenSSL's EVP) of bytes and of files, as lowercase hex. What identifies
// a file the domain delivers to a node, and what the node verifies before it keeps one.
#pragma once

#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

#include "common/diagnostic.hpp"

namespace rsca::content {

// A hash computed piece by piece; final() ends it.
class Sha256 {
public:
  Sha256();
  ~Sha256();
  Sha256(Sha256 &&) noexcept;
  Sha256 &operator=(Sha256 &&) noexcept;
  Sha256(const Sha256 &) = delete;
  Sha256 &operator=(const Sha256 &) = delete;

  void update(const void *data, std::size_t size);
  void update(std::string_view text) { update(text.data(), text.size()); }
  std::string final_hex(); // lowercase hex; the object is then spent

private:
  struct Context;
  std::unique_ptr<Context> context_;
};

std::string sha256_hex(std::string_view bytes);
// The hash of a file's content, read in large blocks; an error names the file.
Expected<std::string> sha256_of_file(const std::filesystem::path &file);

} // namespace rsca::content
