// What tells a file's content changed, short of reading it: its modification time and its size.
// A copy that keeps both (cp -p) of other content goes unnoticed; rsca writes its repository
// itself.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

namespace rsca::profile {

struct FileStamp {
  std::int64_t modified_ns = 0; // the file clock's count (nanoseconds with libstdc++)
  std::uintmax_t size = 0;
  friend bool operator==(const FileStamp &, const FileStamp &) = default;
};

// The file's stamp now; none when it cannot be read.
std::optional<FileStamp> stamp_of(const std::filesystem::path &file);

// A file a profile was read from, with its stamp taken before it was read: content changed while
// being read shows as a stamp that no longer matches.
struct SourceFile {
  std::string path;
  std::optional<FileStamp> stamp;
};

} // namespace rsca::profile
