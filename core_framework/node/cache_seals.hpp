// Internal to the package cache (node/package_cache.hpp): what the cache verified, so that a file
// it runs is checked on every use without reading it each time. A cached file is read-only, and
// the cache records, per file it verified, what identifies its content cheaply: its inode, size,
// modification and change times. A write or a truncate changes the change time, which no user can
// set back; so a file whose stat still matches is what was verified, and one whose stat changed is
// hashed again before it is used.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <utility>

#include "protocol/status.hpp"

namespace rsca::node::detail {

struct InodeStamp {
  std::uint64_t device = 0;
  std::uint64_t inode = 0;
  std::int64_t size = 0;
  std::int64_t modified_ns = 0;
  std::int64_t changed_ns = 0;
  friend bool operator==(const InodeStamp &, const InodeStamp &) = default;
};

// The file's stamp now (it is not followed if a link); none when it cannot be read.
std::optional<InodeStamp> inode_stamp(const std::filesystem::path &file);

class CacheSeals {
public:
  // `file` was just verified to hold `sha256`.
  void record(const std::filesystem::path &file, const std::string &sha256);
  // Whether `file` still holds `sha256`: stat only when nothing changed since it was verified, a
  // hash of it when something did (or it was never verified since the node started). The error
  // names the file as `name`, the hash expected and the hash found.
  protocol::CallResult<void> verify(const std::filesystem::path &file, const std::string &sha256,
                                    const std::string &name);

private:
  struct Seal {
    InodeStamp stamp;
    std::string sha256;
  };
  std::mutex mutex_;
  std::map<std::pair<std::uint64_t, std::uint64_t>, Seal> seals_; // by device and inode
};

} // namespace rsca::node::detail
