// Which sink the daemons log to (service/systemd.hpp): the journal only when JOURNAL_STREAM
// names the very file their stderr is, as systemd documents.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "process/fd.hpp"
#include "service/systemd.hpp"

namespace {

namespace fs = std::filesystem;

struct OpenFile {
  fs::path path = fs::temp_directory_path() / fmt::format("rsca-journal-stream-{}", ::getpid());
  rsca::process::Fd fd{::open(path.c_str(), O_CREAT | O_WRONLY | O_CLOEXEC, 0600)};
  struct stat st {};
  OpenFile() { REQUIRE(::fstat(fd.get(), &st) == 0); }
  ~OpenFile() { ::unlink(path.c_str()); }
};

} // namespace

TEST_CASE("JOURNAL_STREAM names a descriptor's file by device and inode") {
  OpenFile file;
  const auto device = static_cast<unsigned long long>(file.st.st_dev);
  const auto inode = static_cast<unsigned long long>(file.st.st_ino);
  CHECK(
      rsca::service::is_journal_stream(fmt::format("{}:{}", device, inode).c_str(), file.fd.get()));
  CHECK_FALSE(rsca::service::is_journal_stream(fmt::format("{}:{}", device, inode + 1).c_str(),
                                               file.fd.get()));
  CHECK_FALSE(rsca::service::is_journal_stream(fmt::format("{}:{}", device + 1, inode).c_str(),
                                               file.fd.get()));
}

TEST_CASE("a JOURNAL_STREAM that is unset, malformed or names a closed descriptor is no journal") {
  OpenFile file;
  const std::string both = fmt::format("{}:{}", file.st.st_dev, file.st.st_ino);
  CHECK_FALSE(rsca::service::is_journal_stream(nullptr, file.fd.get()));
  const std::vector<std::string> malformed{
      "",
      ":",
      "12",
      fmt::format("{}:", file.st.st_dev),
      fmt::format(":{}", file.st.st_ino),
      both + ":1",
      both + " ",
      "-" + both,
      fmt::format("0x{:x}:{}", file.st.st_dev, file.st.st_ino)};
  for (const auto &bad : malformed) {
    INFO(bad);
    CHECK_FALSE(rsca::service::is_journal_stream(bad.c_str(), file.fd.get()));
  }
  CHECK_FALSE(rsca::service::is_journal_stream(both.c_str(), -1));
}
