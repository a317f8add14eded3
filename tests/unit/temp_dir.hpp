// A folder of its own under the system's temporary directory, for one test: made fresh (mkdtemp,
// so two runs at once never share one), and removed with everything in it when the test ends,
// also when it fails.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>

#include <catch2/catch.hpp>

namespace rsca::test {

class TempDir {
public:
  // The folder is <temporary directory>/<prefix>XXXXXX, its path canonical.
  explicit TempDir(const std::string &prefix = "rsca-test-") {
    auto pattern = (std::filesystem::temp_directory_path() / (prefix + "XXXXXX")).string();
    REQUIRE(::mkdtemp(pattern.data()) != nullptr);
    path_ = std::filesystem::canonical(pattern);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir &) = delete;
  TempDir &operator=(const TempDir &) = delete;

  const std::filesystem::path &path() const { return path_; }

private:
  std::filesystem::path path_;
};

} // namespace rsca::test
